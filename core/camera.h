#ifndef DALA_CORE_CAMERA_H_
#define DALA_CORE_CAMERA_H_

// Camera models: a pinhole camera with OpenCV radial-tangential distortion, and the rectified
// stereo rig that every dataset reader hands to the pipeline.
//
// Frames (DESIGN.md): camera frame x right, y down, z forward; pixel (0, 0) is the centre of the
// top-left pixel (OpenCV).

#include <Eigen/Core>
#include <string>

#include "core/geometry.h"

namespace dala {

// A pinhole camera with the OpenCV "plumb bob" radial-tangential distortion [k1 k2 p1 p2 k3]
// (the EuRoC `radial-tangential` model; all zero for rectified images).
//
// Projection of p_c = (X, Y, Z), Z > 0:
//   x = X / Z, y = Y / Z, r^2 = x^2 + y^2, radial = 1 + k1 r^2 + k2 r^4 + k3 r^6
//   x_d = x radial + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y radial + p1 (r^2 + 2 y^2) + 2 p2 x y
//   u = fx x_d + cx,  v = fy y_d + cy
// Valid for every point in front of the camera (Z > 1e-9); with distortion, only inside the
// region where the distortion map is monotonic (the image and a margin around it for real lenses).
struct PinholeCamera {
  int width = 0, height = 0;  // Pixels.
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // [k1 k2 p1 p2 k3], OpenCV order.
  Eigen::Matrix<double, 5, 1> distortion = Eigen::Matrix<double, 5, 1>::Zero();

  // p_c (camera frame, z forward) -> pixel. Returns false when z <= 1e-9 (behind the camera);
  // `uv` and the Jacobian are then untouched. No bounds check (see InImage).
  bool Project(const Eigen::Vector3d& p_c, Eigen::Vector2d* uv,
               Eigen::Matrix<double, 2, 3>* d_uv_d_p = nullptr) const;

  // Pixel -> bearing ray (x, y, 1) in the camera frame (not normalised). With distortion, the
  // distortion map is inverted by Gauss-Newton from the distorted point (converges to ~1e-12 in a
  // few iterations inside the image of a real lens).
  Eigen::Vector3d Unproject(const Eigen::Vector2d& uv) const;

  // True when uv lies at least `border` pixels inside the image: border <= u <= width-1-border
  // (same for v), pixel centres being integers.
  bool InImage(const Eigen::Vector2d& uv, double border = 0) const;

  // The 3x3 intrinsic matrix [fx 0 cx; 0 fy cy; 0 0 1].
  Eigen::Matrix3d K() const;

  bool HasDistortion() const { return !distortion.isZero(0.0); }

  // Checks positive size and focal lengths, a finite principal point and finite distortion.
  bool IsValid(std::string* why) const;
};

// A rectified stereo pair: both cameras share `left`'s intrinsics (no distortion), the right camera
// sits at +baseline along x of c0: T_c0_c1 = [I | (b, 0, 0)]. A monocular dataset has baseline 0
// (then only `left` is meaningful).
//
// Stereo projection of p_c0 = (X, Y, Z): u = fx X/Z + cx, v = fy Y/Z + cy, disparity
// d = u_left - u_right = fx b / Z.
struct StereoRig {
  PinholeCamera left;
  double baseline = 0;  // Metres, > 0 for stereo, 0 for monocular datasets.

  bool is_stereo() const { return baseline > 0; }
  Pose T_c0_c1() const;

  // (u, v, d) of a point in the left camera frame; false when z <= 1e-9.
  // Precondition (CHECK): left has no distortion.
  bool ProjectStereo(const Eigen::Vector3d& p_c0, Eigen::Vector3d* uvd,
                     Eigen::Matrix3d* d_uvd_d_p = nullptr) const;

  // Inverse of ProjectStereo: Z = fx b / d, X = (u - cx) Z / fx, Y = (v - cy) Z / fy.
  // Returns false when d <= 0 or the rig is monocular (no finite depth).
  bool Triangulate(const Eigen::Vector3d& uvd, Eigen::Vector3d* p_c0,
                   Eigen::Matrix3d* d_p_d_uvd = nullptr) const;

  // First-order covariance of a triangulated point (left camera frame, m^2):
  //   J diag(s_px^2, s_px^2, s_d^2) J^T, J = d_p_d_uvd.
  // Depth variance grows as Z^4 s_d^2 / (fx b)^2, i.e. the standard deviation as Z^2.
  // Precondition (CHECK): d > 0 and a stereo rig.
  Eigen::Matrix3d TriangulationCovariance(const Eigen::Vector3d& uvd, double sigma_px,
                                          double sigma_disparity) const;

  bool IsValid(std::string* why) const;
};

}  // namespace dala

#endif  // DALA_CORE_CAMERA_H_
