#ifndef DALA_BACKEND_BA_BA_TYPES_H_
#define DALA_BACKEND_BA_BA_TYPES_H_

// Plain inputs of the bundle-adjustment machinery (backend/ba). They do not depend on the frontend:
// the System converts the frontend's FrameMeasurement into these.
//
// Camera model (rectified stereo, DESIGN.md frames): a point p_c = (x, y, z) in the left camera
// c0 (x right, y down, z forward) projects to
//   u = fx * x / z + cx,   v = fy * y / z + cy,   u_r = u - fx * b / z   (right image, same v),
// where b is the baseline (metres, > 0 for stereo, 0 for a monocular camera). Pixels follow the
// OpenCV convention (centre of the top-left pixel is (0, 0)). Valid for z > 0.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/types.h"

namespace dala {

struct StereoIntrinsics {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double baseline = 0.0;  // metres; 0 => monocular.
  // Observed disparities are this much smaller than fx b / z (a real rig's rectification
  // residual, SlidingWindowBa::Options::estimate_disparity_offset): the right image's abscissa
  // is u_r = u - fx b / z + disparity_offset_px.
  double disparity_offset_px = 0.0;

  bool is_stereo() const { return baseline > 0.0; }
  bool IsValid(std::string* why) const;
};

// One observation of a landmark in a keyframe (or frame) image.
struct BaObservation {
  LandmarkId landmark;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // left image pixel.
  // Right-image column u_r of the same point (rectified: same row). Absent => monocular
  // observation. Needs StereoIntrinsics::baseline > 0.
  std::optional<double> u_right;
  // Standard deviation of each pixel coordinate (u, v and u_r, independent); residuals are
  // divided by it (whitened).
  double sigma_px = 1.0;

  bool is_stereo() const { return u_right.has_value(); }
};

// A keyframe as the estimator receives it: its id and time, an initial guess of the left camera
// pose in the world T_w_c (maps camera points into the world), and what it observes.
struct BaKeyframe {
  KeyframeId id;
  int64_t t_ns = 0;
  Pose T_w_c = Pose::Identity();
  std::vector<BaObservation> observations;
};

// 95% quantiles of the chi-square distribution, used to reject whitened residuals.
constexpr double kChi2Quantile95Dof2 = 5.991;  // mono (u, v)
constexpr double kChi2Quantile95Dof3 = 7.815;  // stereo (u, v, u_r)

// Point in the left camera from a stereo observation: z = fx b / (u - u_r). Returns nullopt when
// the disparity is below min_disparity_px (point too far or behind) or the camera is mono.
std::optional<Eigen::Vector3d> TriangulateStereo(const StereoIntrinsics& K,
                                                 const BaObservation& obs, double min_disparity_px);

// Linear (DLT) triangulation of one point from its left-image pixels `uv[i]` in cameras
// `T_w_c[i]` (>= 2 views): each view gives x_n (P_3 X) - P_1 X = 0 and y_n (P_3 X) - P_2 X = 0,
// with P = [R_w_c^T | -R_w_c^T t_w_c] and (x_n, y_n) the normalised coordinates; X is the right
// singular vector of the smallest singular value. nullopt when the largest angle between two of
// the rays is below min_parallax_deg, X is at infinity, or the point lies closer than min_depth
// to (or behind) one of the cameras.
std::optional<Eigen::Vector3d> TriangulateViews(const StereoIntrinsics& K,
                                                const std::vector<Pose>& T_w_c,
                                                const std::vector<Eigen::Vector2d>& uv,
                                                double min_parallax_deg, double min_depth);

}  // namespace dala

#endif  // DALA_BACKEND_BA_BA_TYPES_H_
