#include "frontend/motion_estimator.h"

#include <glog/logging.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>

#include "core/cv_pose.h"
#include "core/ransac_order.h"

namespace dala {
namespace {

// 95 % chi-square quantiles for the residual dimensions we use.
double Chi2Gate95(int dof, double gate_3dof) {
  return dof == 3 ? gate_3dof : (dof == 2 ? 5.991 : 3.841);
}

}  // namespace

bool MotionEstimatorOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (ransac_threshold_px <= 0) return fail("motion.ransac_threshold_px must be > 0");
  if (ransac_confidence <= 0 || ransac_confidence >= 1)
    return fail("motion.ransac_confidence must be in (0, 1)");
  if (ransac_max_iterations < 1) return fail("motion.ransac_max_iterations must be >= 1");
  if (refine_iterations < 1) return fail("motion.refine_iterations must be >= 1");
  if (chi2_gate <= 0) return fail("motion.chi2_gate must be > 0");
  if (sigma_px <= 0) return fail("motion.sigma_px must be > 0");
  if (min_inliers < 4) return fail("motion.min_inliers must be >= 4");
  return true;
}

MotionEstimator::MotionEstimator(const StereoRig& rig, const MotionEstimatorOptions& options)
    : rig_(rig), options_(options) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
}

bool MotionEstimator::Linearize(const MotionCorrespondence& m, const Pose& T_prev_cur,
                                Eigen::VectorXd* r, Eigen::MatrixXd* J,
                                Eigen::MatrixXd* W) const {
  const Pose T_cur_prev = T_prev_cur.inverse();
  const Eigen::Vector3d q = T_cur_prev * m.p_prev;  // The point in the current camera.
  Eigen::Matrix<double, 3, 6> d_q_d_delta;
  d_q_d_delta << Skew(q), -Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d d_q_d_pprev = T_cur_prev.linear();
  const double s2 = options_.sigma_px * options_.sigma_px;
  if (m.u_right_cur && rig_.baseline > 0) {
    Eigen::Vector3d uvd;
    Eigen::Matrix3d d_uvd_d_q;
    if (!rig_.ProjectStereo(q, &uvd, &d_uvd_d_q)) return false;
    *r = uvd - Eigen::Vector3d(m.uv_cur.x(), m.uv_cur.y(), m.uv_cur.x() - *m.u_right_cur);
    *J = d_uvd_d_q * d_q_d_delta;
    const Eigen::Matrix3d Jp = d_uvd_d_q * d_q_d_pprev;
    // Disparity is a difference of two abscissae: variance 2 s^2, correlated with u.
    Eigen::Matrix3d R_meas;
    R_meas << s2, 0, s2, 0, s2, 0, s2, 0, 2 * s2;
    *W = (R_meas + Jp * m.cov_p_prev * Jp.transpose()).inverse();
  } else {
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> d_uv_d_q;
    if (!rig_.left.Project(q, &uv, &d_uv_d_q)) return false;
    *r = uv - m.uv_cur;
    *J = d_uv_d_q * d_q_d_delta;
    const Eigen::Matrix<double, 2, 3> Jp = d_uv_d_q * d_q_d_pprev;
    *W = (s2 * Eigen::Matrix2d::Identity() + Jp * m.cov_p_prev * Jp.transpose()).inverse();
  }
  return true;
}

int MotionEstimator::NormalEquations(const std::vector<MotionCorrespondence>& matches,
                                     const Pose& T_prev_cur, const std::vector<bool>& inlier,
                                     Matrix6d* H, Vector6d* b) const {
  H->setZero();
  b->setZero();
  int used = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (!inlier[i]) continue;
    Eigen::VectorXd r;
    Eigen::MatrixXd J, W;
    if (!Linearize(matches[i], T_prev_cur, &r, &J, &W)) continue;
    *H += J.transpose() * W * J;
    *b += J.transpose() * W * r;
    ++used;
  }
  return used;
}

int MotionEstimator::CountInliers(const std::vector<MotionCorrespondence>& matches,
                                  const Pose& T_prev_cur, std::vector<bool>* inlier) const {
  const Pose T_cur_prev = T_prev_cur.inverse();
  const double thr2 = options_.ransac_threshold_px * options_.ransac_threshold_px;
  int count = 0;
  inlier->assign(matches.size(), false);
  for (size_t i = 0; i < matches.size(); ++i) {
    Eigen::Vector2d uv;
    if (!rig_.left.Project(T_cur_prev * matches[i].p_prev, &uv)) continue;
    if ((uv - matches[i].uv_cur).squaredNorm() < thr2) {
      (*inlier)[i] = true;
      ++count;
    }
  }
  return count;
}

std::optional<MotionResult> MotionEstimator::Estimate3D2D(
    const std::vector<MotionCorrespondence>& matches, const Pose* prior_T_prev_cur) const {
  const int n = static_cast<int>(matches.size());
  if (n < std::max(4, options_.min_inliers)) return std::nullopt;

  // 1. RANSAC with P3P minimal samples, from a seeded generator.
  std::mt19937_64 rng(options_.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << rig_.left.fx, 0, rig_.left.cx, 0, rig_.left.fy,
                     rig_.left.cy, 0, 0, 1);
  Pose best = Pose::Identity();
  int best_count = -1;
  std::vector<bool> inlier;
  if (prior_T_prev_cur != nullptr) {
    best = *prior_T_prev_cur;
    best_count = CountInliers(matches, best, &inlier);
  }
  int needed = options_.ransac_max_iterations;
  for (int it = 0; it < needed && it < options_.ransac_max_iterations; ++it) {
    int idx[3];
    idx[0] = pick(rng);
    do idx[1] = pick(rng); while (idx[1] == idx[0]);
    do idx[2] = pick(rng); while (idx[2] == idx[0] || idx[2] == idx[1]);
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (int k : idx) {
      const auto& m = matches[k];
      object.emplace_back(m.p_prev.x(), m.p_prev.y(), m.p_prev.z());
      image.emplace_back(m.uv_cur.x(), m.uv_cur.y());
    }
    std::vector<cv::Mat> rvecs, tvecs;
    int solutions = 0;
    try {
      solutions = cv::solveP3P(object, image, K, cv::noArray(), rvecs, tvecs, cv::SOLVEPNP_P3P);
    } catch (const cv::Exception&) {
      continue;  // Degenerate sample (collinear points).
    }
    for (int s = 0; s < solutions; ++s) {
      const Pose T_prev_cur = PoseFromRvecTvec(rvecs[s], tvecs[s]).inverse();
      std::vector<bool> in;
      const int count = CountInliers(matches, T_prev_cur, &in);
      if (count > best_count) {
        best_count = count;
        best = T_prev_cur;
        inlier = in;
        const double w = static_cast<double>(count) / n;
        const double p_fail = 1.0 - w * w * w;
        if (p_fail <= 1e-12) {
          needed = 0;
        } else {
          needed = static_cast<int>(
              std::ceil(std::log(1.0 - options_.ransac_confidence) / std::log(p_fail)));
        }
      }
    }
  }
  if (best_count < options_.min_inliers) return std::nullopt;

  // 2. Gauss-Newton on the inliers, re-selecting them by the chi-square gate.
  Pose T = best;
  Matrix6d H = Matrix6d::Zero();
  for (int iter = 0; iter < options_.refine_iterations; ++iter) {
    Vector6d b;
    if (NormalEquations(matches, T, inlier, &H, &b) < options_.min_inliers) return std::nullopt;
    const Eigen::LDLT<Matrix6d> ldlt(H);
    if (ldlt.info() != Eigen::Success) return std::nullopt;
    const Vector6d delta = -ldlt.solve(b);
    if (!delta.allFinite()) return std::nullopt;
    T = Orthonormalized(T * ExpSE3(delta));
    // Re-select inliers at the new estimate.
    int count = 0;
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd r;
      Eigen::MatrixXd J, W;
      const bool ok = Linearize(matches[i], T, &r, &J, &W);
      inlier[i] = ok && r.dot(W * r) < Chi2Gate95(static_cast<int>(r.size()), options_.chi2_gate);
      count += inlier[i];
    }
    if (count < options_.min_inliers) return std::nullopt;
    if (delta.norm() < 1e-10) break;
  }
  // 3. Covariance at the solution, over the final inliers.
  Vector6d unused_b;
  const int count = NormalEquations(matches, T, inlier, &H, &unused_b);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(H);
  if (eig.info() != Eigen::Success || eig.eigenvalues().minCoeff() <= 1e-12) return std::nullopt;

  MotionResult result;
  result.estimate.T_prev_cur = T;
  result.estimate.cov = H.inverse();
  result.estimate.cov = 0.5 * (result.estimate.cov + result.estimate.cov.transpose()).eval();
  result.estimate.inliers = count;
  result.estimate.correspondences = n;
  result.estimate.scale_known = true;
  result.inlier = inlier;
  return result;
}

std::optional<MotionResult> MotionEstimator::EstimateEssential(
    const std::vector<Eigen::Vector2d>& uv_prev, const std::vector<Eigen::Vector2d>& uv_cur) const {
  CHECK_EQ(uv_prev.size(), uv_cur.size()) << "EstimateEssential needs paired points";
  const int n = static_cast<int>(uv_prev.size());
  if (n < std::max(8, options_.min_inliers)) return std::nullopt;
  // The correspondences in the order that seeds OpenCV's draws (core/ransac_order.h).
  const std::vector<int> order = RansacOrder(uv_prev.size(), options_.ransac_order_seed);
  std::vector<cv::Point2d> a, b;
  for (const int i : order) {
    a.emplace_back(uv_prev[i].x(), uv_prev[i].y());
    b.emplace_back(uv_cur[i].x(), uv_cur[i].y());
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << rig_.left.fx, 0, rig_.left.cx, 0, rig_.left.fy,
                     rig_.left.cy, 0, 0, 1);
  cv::Mat mask;
  const cv::Mat E = cv::findEssentialMat(a, b, K, cv::RANSAC, options_.ransac_confidence,
                                         options_.ransac_threshold_px, mask);
  if (E.rows != 3 || E.cols != 3) return std::nullopt;
  cv::Mat R_cv, t_cv;
  // recoverPose gives R, t with x_cur = R x_prev + t, i.e. T_cur_prev.
  const int good = cv::recoverPose(E, a, b, K, R_cv, t_cv, mask);
  if (good < options_.min_inliers) return std::nullopt;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  cv::cv2eigen(R_cv, R);
  cv::cv2eigen(t_cv, t);
  MotionResult result;
  result.estimate.T_prev_cur = MakePose(R, t.normalized()).inverse();
  // The essential matrix gives no metric covariance; a loose, documented default.
  result.estimate.cov = Matrix6d::Identity() * 1e-2;
  result.estimate.inliers = good;
  result.estimate.correspondences = n;
  result.estimate.scale_known = false;
  result.inlier = MaskInGivenOrder(mask, order);
  return result;
}

std::optional<MotionResult> MotionEstimator::EstimateRotation(
    const std::vector<Eigen::Vector2d>& uv_prev, const std::vector<Eigen::Vector2d>& uv_cur) const {
  CHECK_EQ(uv_prev.size(), uv_cur.size()) << "EstimateRotation needs paired points";
  const int n = static_cast<int>(uv_prev.size());
  if (n < std::max(4, options_.min_inliers)) return std::nullopt;
  const std::vector<int> order = RansacOrder(uv_prev.size(), options_.ransac_order_seed);
  std::vector<cv::Point2d> a, b;
  for (const int i : order) {
    a.emplace_back(uv_prev[i].x(), uv_prev[i].y());
    b.emplace_back(uv_cur[i].x(), uv_cur[i].y());
  }
  cv::Mat mask;
  const cv::Mat H_cv = cv::findHomography(a, b, cv::RANSAC, options_.ransac_threshold_px, mask,
                                          options_.ransac_max_iterations,
                                          options_.ransac_confidence);
  if (H_cv.rows != 3 || H_cv.cols != 3) return std::nullopt;
  const int inliers = cv::countNonZero(mask);
  if (inliers < options_.min_inliers) return std::nullopt;
  Eigen::Matrix3d H;
  cv::cv2eigen(H_cv, H);
  const Eigen::Matrix3d K = rig_.left.K();
  const Eigen::Matrix3d M = K.inverse() * H * K;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d R_cur_prev = svd.matrixU() * svd.matrixV().transpose();
  if (R_cur_prev.determinant() < 0) R_cur_prev = -R_cur_prev;
  MotionResult result;
  result.estimate.T_prev_cur = MakePose(R_cur_prev.transpose(), Eigen::Vector3d::Zero());
  result.estimate.cov = Matrix6d::Identity() * 1e-2;  // As EstimateEssential: no metric model.
  result.estimate.inliers = inliers;
  result.estimate.correspondences = n;
  result.estimate.scale_known = false;
  result.inlier = MaskInGivenOrder(mask, order);
  return result;
}

}  // namespace dala
