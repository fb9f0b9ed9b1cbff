#ifndef DALA_FRONTEND_MOTION_ESTIMATOR_H_
#define DALA_FRONTEND_MOTION_ESTIMATOR_H_

// Visual motion estimation between two stereo frames (the paper's prediction for the stereo
// EKF, and the initial guess of every other estimator).
//
// Stereo, 3D-to-2D: points triangulated in the previous left camera, p_prev (with covariance
// Sigma_p), are observed in the current stereo pair as z = (u, v, d). We estimate
// T_prev_cur = T_hat * Exp(delta) (right perturbation, delta = [phi; rho]) minimising
//   sum_i  r_i^T W_i r_i,   r_i = pi_s(T_prev_cur^-1 * p_prev_i) - z_i,
//   W_i = (sigma_px^2 I + J_p,i Sigma_p,i J_p,i^T)^-1,
// where pi_s is the rectified stereo projection (u, v, fx b / z) and J_p its derivative with
// respect to p_prev: the uncertainty of the triangulated points is part of the noise, so the
// pose covariance (J^T W J)^-1 is not over-confident with distant points.
//   1. seeded RANSAC over minimal sets of 3 (P3P, OpenCV's solveP3P), scored on the left image;
//   2. Gauss-Newton on the inliers, re-selecting inliers by a chi-square test on r^T W r;
//   3. covariance of delta: (sum J_i^T W_i J_i)^-1 at the solution.
// Derivative of the current-frame point: with q = T_hat^-1 p_prev,
//   p_cur(delta) = Exp(-delta) q ~= q + [q]x phi - rho  =>  d p_cur / d delta = [ [q]x  -I ].
//
// Monocular: relative pose from the essential matrix (OpenCV RANSAC, then recoverPose), with
// a unit translation (scale_known = false).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"
#include "core/frame_measurement.h"

namespace dala {

struct MotionEstimatorOptions {
  // RANSAC inlier threshold on the left-image reprojection error, pixels.
  double ransac_threshold_px = 2.0;
  // RANSAC stops when this confidence of having drawn an all-inlier sample is reached...
  double ransac_confidence = 0.999;
  // ...or after this many samples.
  int ransac_max_iterations = 300;
  // Seed of the P3P RANSAC's sampler (std::mt19937_64): the same input and seed give the same
  // estimate.
  uint64_t seed = 42;
  // One camera: the order of the correspondences handed to OpenCV's essential-matrix and
  // homography RANSAC, which is what seeds their draws (core/ransac_order.h): 0 as given.
  uint64_t ransac_order_seed = 0;
  // Gauss-Newton iterations of the refinement (each with an inlier re-selection).
  int refine_iterations = 10;
  // Chi-square gate on r^T W r for inliers after refinement (3 dof: 95 % = 7.815).
  double chi2_gate = 7.815;
  // Pixel noise of the current observations.
  double sigma_px = 1.0;
  // Fewer inliers than this: the motion is not estimated (status kLost).
  int min_inliers = 12;

  bool IsValid(std::string* why) const;
};

// A 3D point of the previous frame matched to an observation of the current frame.
struct MotionCorrespondence {
  Eigen::Vector3d p_prev = Eigen::Vector3d::Zero();      // Previous left camera frame, metres.
  Eigen::Matrix3d cov_p_prev = Eigen::Matrix3d::Zero();  // Its covariance.
  Eigen::Vector2d uv_cur = Eigen::Vector2d::Zero();      // Current left image, pixels.
  std::optional<double> u_right_cur;                     // Current right image, when stereo.
};

struct MotionResult {
  MotionEstimate estimate;
  std::vector<bool> inlier;  // One per correspondence.
};

class MotionEstimator {
 public:
  MotionEstimator(const StereoRig& rig, const MotionEstimatorOptions& options);

  // Stereo (or 3D-to-mono-2D when u_right_cur is absent): nullopt when there are too few
  // correspondences or inliers, or the geometry is degenerate. `prior_T_prev_cur`, when given,
  // is scored as an extra RANSAC hypothesis (e.g. constant velocity).
  std::optional<MotionResult> Estimate3D2D(const std::vector<MotionCorrespondence>& matches,
                                           const Pose* prior_T_prev_cur = nullptr) const;

  // Monocular: relative pose from 2D-2D matches (pixels) via the essential matrix; the
  // translation has unit norm. nullopt when degenerate.
  std::optional<MotionResult> EstimateEssential(const std::vector<Eigen::Vector2d>& uv_prev,
                                                const std::vector<Eigen::Vector2d>& uv_cur) const;

  // Monocular, when the essential matrix is degenerate (a camera turning on the spot, or not
  // moving): the homography of a pure rotation, x_cur ~ K R_cur_prev K^-1 x_prev (OpenCV RANSAC,
  // its draws set by ransac_order_seed), R_cur_prev = the rotation nearest to K^-1 H K (SVD, scaled
  // to det 1). The motion has that rotation and no translation (scale_known = false). nullopt with
  // too few inliers.
  std::optional<MotionResult> EstimateRotation(const std::vector<Eigen::Vector2d>& uv_prev,
                                               const std::vector<Eigen::Vector2d>& uv_cur) const;

 private:
  // Residual (u, v[, d]) and its Jacobian w.r.t. delta; false when the point is behind.
  bool Linearize(const MotionCorrespondence& m, const Pose& T_prev_cur, Eigen::VectorXd* r,
                 Eigen::MatrixXd* J, Eigen::MatrixXd* W) const;
  // Gauss-Newton normal equations H delta = -b over the inliers; returns how many were used.
  int NormalEquations(const std::vector<MotionCorrespondence>& matches, const Pose& T_prev_cur,
                      const std::vector<bool>& inlier, Matrix6d* H, Vector6d* b) const;
  int CountInliers(const std::vector<MotionCorrespondence>& matches, const Pose& T_prev_cur,
                   std::vector<bool>* inlier) const;

  StereoRig rig_;
  MotionEstimatorOptions options_;
};

}  // namespace dala

#endif  // DALA_FRONTEND_MOTION_ESTIMATOR_H_
