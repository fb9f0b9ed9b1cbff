#ifndef DALA_FRONTEND_STEREO_H_
#define DALA_FRONTEND_STEREO_H_

// Stereo matching on a rectified pair: the robust matcher with the epipolar prior (same row,
// disparity in the range that the depth limits allow), a sub-pixel disparity refined by
// correlation along the row, and the triangulated point with its first-order covariance.
//
// Sub-pixel disparity: the right abscissa u_r of a match is refined by minimising the SSD between
// the left window centred at (u_l, v_l) and right windows centred at (u_r + k, v_l), k in
// {-1, 0, +1} (bilinear sampling), and taking the vertex of the parabola through the three SSDs.
// Using the left point's own row keeps the pair on one epipolar line, so the disparity is
// measured at the left point's sub-pixel position (the one the estimators use). A real rig's
// rows disagree a little (KITTI 06: -0.5 to +0.2 px across the image, scripts/stereo_rows.py);
// refining in 2D there (the 3 x 3 SSD grid's quadratic) changed no median KITTI result beyond
// a start's spread (docs/results.md, "stop 60").
//
// Depth limit (close and far points, as ORB-SLAM2's ThDepth): a systematic disparity error
// delta (calibration and rectification residuals, typically 0.1-0.3 px on real rigs) biases the
// depth z = fx b / d by the relative amount delta / d = delta z / (fx b), so far points bias the
// metric scale of everything they constrain. Measured on KITTI 06 (docs/results.md): the visual
// motion from points of disparity d overestimates the translation by 0.3 px / d (4 % at d = 8 px,
// 0.1 % at d > 30 px), while the disparities agree with independent Lucas-Kanade and SGBM
// estimates to 0.05 px and the rendered sequences show no signed bias. So a point keeps its
// depth only up to max_depth_baselines baselines; farther points are still matched (a far match
// is no reason for a wrong near one) but are returned without stereo: the frontend tracks them
// as monocular points (rotation-only prediction, epipolar gate).

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"
#include "frontend/harris.h"
#include "frontend/matcher.h"

namespace dala {

// The smallest disparity matched without a depth limit (StereoOptions::max_depth_m = 0): a point
// whose disparity is within the sub-pixel noise (~0.05 px) of zero has no usable depth anyway.
constexpr double kMinStereoDisparityPx = 0.02;

struct StereoOptions {
  MatcherOptions matcher = MatcherOptions::ForStereo();
  double max_dv_px = 1.5;     // Rows of a rectified pair agree to this (calibration error).
  double min_depth_m = 0.3;   // Points nearer than this are rejected (disparity upper bound).
  // Stereo search range: disparities down to fx b / max_depth_m; 0 (default): no limit, down to
  // kMinStereoDisparityPx. A limit on the MEASURED depth keeps the far points whose disparity
  // noise came out large and drops those whose noise came out small, so the far points kept
  // are biased near (rendered flight: the BA's disparity offset estimate -0.07 px with an 80 m
  // limit here and a 60 m one in the BA, -0.002 px without), and it drops the far points that
  // hold the rotation (flight ATE 0.1275 m with both limits, 0.0289 m without; docs/backend.md).
  double max_depth_m = 0.0;
  // Depth is kept only for points nearer than this many baselines (and max_depth_m); see the
  // comment above. 0: no limit (the default: an exact rig, as rendered, loses accuracy with
  // the limit: small_loop at 480x320 0.031 m ATE without it, 0.148 m with one). Real rigs with
  // calibration residuals whose disparity offset is not calibrated
  // (ba.calibrate_disparity_offset off) can set it per camera, as ORB-SLAM2's ThDepth (45
  // baselines is 24 m on KITTI's rig).
  double max_depth_baselines = 0.0;
  // ...unless fewer points than this are nearer: then the nearest far points keep their depth
  // until this many have one (the visual motion needs 3D-2D correspondences; a wide open place
  // or a low-resolution rig can leave too few near points, and a lost frame costs more than
  // the far points' scale bias).
  int min_points_with_depth = 100;
  // Side of the SSD window along the row that refines u_right to sub-pixel (odd).
  int refine_window = 7;
  // Image noise (u, v), pixels: each observation's sigma_px, the EKFs' measurement noise (the
  // sliding window has its own, ba.sigma_px).
  double sigma_px = 1.0;
  double sigma_disparity = 1.0;  // Disparity noise after refinement, pixels.

  bool IsValid(std::string* why) const;
};

// The stereo result for one left point.
struct StereoPoint {
  double u_right = 0;
  Eigen::Vector3d p_c0 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_p_c0 = Eigen::Matrix3d::Zero();
};

// One entry per left point: empty when the point has no stereo match (or an invalid depth).
std::vector<std::optional<StereoPoint>> MatchStereo(const StereoRig& rig,
                                                    const DetectedImage& left,
                                                    const DetectedImage& right,
                                                    const cv::Mat& left_gray,
                                                    const cv::Mat& right_gray,
                                                    const StereoOptions& options);

}  // namespace dala

#endif  // DALA_FRONTEND_STEREO_H_
