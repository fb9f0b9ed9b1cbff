#ifndef DALA_TESTS_BACKEND_MONO_TWO_VIEW_SCENE_H_
#define DALA_TESTS_BACKEND_MONO_TWO_VIEW_SCENE_H_

// Synthetic correspondences of the two-view tests: points in front of the reference camera
// (depth 4..12 m, or on the plane z = 6 when planar), seen from the reference and from
// T_cur_ref, with Gaussian pixel noise. Deterministic for a given seed.

#include <random>
#include <vector>

#include "core/camera.h"
#include "core/geometry.h"

namespace dala::testing {

// A distortion-free camera of the given image size and focal length, its principal point at the
// image centre (OpenCV pixel centres: ((width - 1) / 2, (height - 1) / 2)).
inline PinholeCamera CentredCamera(int width, int height, double f) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = f;
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

// A camera of EuRoC's image size (752 x 480, f = 450 px).
inline PinholeCamera EurocGeometryCamera() { return CentredCamera(752, 480, 450.0); }

// A camera of KITTI's geometry (1226 x 370, f = 707 px).
inline PinholeCamera KittiGeometryCamera() { return CentredCamera(1226, 370, 707.0); }

struct TwoViews {
  std::vector<Eigen::Vector2d> ref, cur;
  std::vector<Eigen::Vector3d> p_ref;
};

inline TwoViews RenderTwoViews(const PinholeCamera& cam, const Pose& T_cur_ref, bool planar,
                               double noise_px, uint32_t seed, int n = 300) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, cam.width - 1), v(0, cam.height - 1), z(4.0, 12.0);
  std::normal_distribution<double> noise(0.0, noise_px);
  TwoViews out;
  while (static_cast<int>(out.ref.size()) < n) {
    const Eigen::Vector2d uv(u(rng), v(rng));
    const Eigen::Vector3d p = cam.Unproject(uv) * (planar ? 6.0 : z(rng));
    Eigen::Vector2d uv_cur;
    if (!cam.Project(T_cur_ref * p, &uv_cur) || !cam.InImage(uv_cur)) continue;
    out.ref.push_back(uv + Eigen::Vector2d(noise(rng), noise(rng)));
    out.cur.push_back(uv_cur + Eigen::Vector2d(noise(rng), noise(rng)));
    out.p_ref.push_back(p);
  }
  return out;
}

}  // namespace dala::testing

#endif  // DALA_TESTS_BACKEND_MONO_TWO_VIEW_SCENE_H_
