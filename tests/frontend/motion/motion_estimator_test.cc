#include "frontend/motion_estimator.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/test_util.h"

namespace dala {
namespace {

StereoRig TestRig() {
  StereoRig rig;
  rig.left.width = 752;
  rig.left.height = 480;
  rig.left.fx = rig.left.fy = 450.0;
  rig.left.cx = 376.0;
  rig.left.cy = 240.0;
  rig.baseline = 0.4;
  return rig;
}

// Points in front of the previous camera, observed in the current stereo pair with pixel noise;
// `outlier_fraction` of them get a random wrong observation.
std::vector<MotionCorrespondence> MakeCorrespondences(const StereoRig& rig, const Pose& T_prev_cur,
                                                      int n, double sigma_px,
                                                      double outlier_fraction, std::mt19937* rng) {
  std::uniform_real_distribution<double> ux(-8, 8), uy(-3, 3), uz(3, 40), uu(0, 1);
  std::normal_distribution<double> noise(0.0, sigma_px);
  std::vector<MotionCorrespondence> out;
  while (static_cast<int>(out.size()) < n) {
    const Eigen::Vector3d p_prev(ux(*rng), uy(*rng), uz(*rng));
    Eigen::Vector3d uvd_prev;
    Eigen::Matrix3d unused;
    if (!rig.ProjectStereo(p_prev, &uvd_prev, &unused)) continue;
    // The previous point is itself triangulated from noisy pixels: perturb it consistently.
    Eigen::Vector3d uvd_noisy = uvd_prev + Eigen::Vector3d(noise(*rng), noise(*rng), noise(*rng));
    MotionCorrespondence m;
    if (!rig.Triangulate(uvd_noisy, &m.p_prev)) continue;
    m.cov_p_prev = rig.TriangulationCovariance(uvd_noisy, sigma_px, sigma_px * std::sqrt(2.0));
    Eigen::Vector3d uvd_cur;
    if (!rig.ProjectStereo(T_prev_cur.inverse() * p_prev, &uvd_cur)) continue;
    if (!rig.left.InImage(uvd_cur.head<2>()) || uvd_cur.z() <= 0.5) continue;
    m.uv_cur = uvd_cur.head<2>() + Eigen::Vector2d(noise(*rng), noise(*rng));
    m.u_right_cur = uvd_cur.x() - uvd_cur.z() + noise(*rng);
    if (uu(*rng) < outlier_fraction) {
      m.uv_cur += Eigen::Vector2d(40 + 100 * uu(*rng), -30 - 50 * uu(*rng));
    }
    out.push_back(m);
  }
  return out;
}

Pose TestMotion() {
  Vector6d xi;
  xi << 0.02, -0.05, 0.01, 0.1, -0.02, 0.9;
  return ExpSE3(xi);
}

TEST(MotionEstimator, RecoversStereoMotionWithOutliers) {
  std::mt19937 rng(3);
  const StereoRig rig = TestRig();
  const Pose truth = TestMotion();
  const auto matches = MakeCorrespondences(rig, truth, 200, 0.5, 0.3, &rng);
  MotionEstimator estimator(rig, MotionEstimatorOptions());
  const auto result = estimator.Estimate3D2D(matches);
  ASSERT_TRUE(result.has_value());
  const Vector6d err = LogSE3(truth.inverse() * result->estimate.T_prev_cur);
  EXPECT_LT(err.head<3>().norm(), 2e-3) << err.transpose();
  EXPECT_LT(err.tail<3>().norm(), 0.02) << err.transpose();
  EXPECT_GT(result->estimate.inliers, 120);
  EXPECT_LT(result->estimate.inliers, 150);  // The 30 % outliers must be rejected.
}

// Normalised estimation error squared over seeded trials: for a consistent covariance the mean
// of e^T P^-1 e is 6 (the dimension); allow the sampling spread of 100 trials and a little more.
TEST(MotionEstimator, CovarianceIsConsistent) {
  const StereoRig rig = TestRig();
  const Pose truth = TestMotion();
  MotionEstimator estimator(rig, MotionEstimatorOptions());
  double nees_sum = 0;
  const int trials = 100;
  for (int t = 0; t < trials; ++t) {
    std::mt19937 rng(100 + t);
    const auto matches = MakeCorrespondences(rig, truth, 80, 1.0, 0.0, &rng);
    const auto result = estimator.Estimate3D2D(matches);
    ASSERT_TRUE(result.has_value());
    const Vector6d e = LogSE3(result->estimate.T_prev_cur.inverse() * truth);
    nees_sum += e.dot(result->estimate.cov.ldlt().solve(e));
  }
  const double mean_nees = nees_sum / trials;
  EXPECT_GT(mean_nees, 3.5);
  EXPECT_LT(mean_nees, 9.0);
}

TEST(MotionEstimator, DeterministicForASeed) {
  std::mt19937 rng(9);
  const StereoRig rig = TestRig();
  const auto matches = MakeCorrespondences(rig, TestMotion(), 150, 0.7, 0.4, &rng);
  MotionEstimator estimator(rig, MotionEstimatorOptions());
  const auto a = estimator.Estimate3D2D(matches);
  const auto b = estimator.Estimate3D2D(matches);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->estimate.T_prev_cur.matrix(), b->estimate.T_prev_cur.matrix());
}

TEST(MotionEstimator, TooFewMatchesIsAStatusNotACrash) {
  std::mt19937 rng(4);
  const StereoRig rig = TestRig();
  const auto matches = MakeCorrespondences(rig, TestMotion(), 6, 0.5, 0.0, &rng);
  MotionEstimator estimator(rig, MotionEstimatorOptions());
  EXPECT_FALSE(estimator.Estimate3D2D(matches).has_value());
  // All outliers: no consensus.
  auto garbage = MakeCorrespondences(rig, TestMotion(), 100, 0.5, 1.0, &rng);
  for (auto& m : garbage) m.uv_cur = Eigen::Vector2d(std::uniform_real_distribution<>(0, 752)(rng),
                                                     std::uniform_real_distribution<>(0, 480)(rng));
  EXPECT_FALSE(estimator.Estimate3D2D(garbage).has_value());
}

TEST(MotionEstimator, EssentialGivesDirectionOfTranslation) {
  std::mt19937 rng(5);
  const StereoRig rig = TestRig();
  const Pose truth = TestMotion();
  const auto matches = MakeCorrespondences(rig, truth, 200, 0.3, 0.1, &rng);
  std::vector<Eigen::Vector2d> uv_prev, uv_cur;
  for (const auto& m : matches) {
    Eigen::Vector2d uv;
    ASSERT_TRUE(rig.left.Project(m.p_prev, &uv));
    uv_prev.push_back(uv);
    uv_cur.push_back(m.uv_cur);
  }
  MotionEstimator estimator(rig, MotionEstimatorOptions());
  const auto result = estimator.EstimateEssential(uv_prev, uv_cur);
  ASSERT_TRUE(result.has_value());
  EXPECT_FALSE(result->estimate.scale_known);
  const Eigen::Vector3d t_est = result->estimate.T_prev_cur.translation();
  EXPECT_GT(t_est.normalized().dot(truth.translation().normalized()), 0.99);
  EXPECT_LT(LogSO3(truth.linear().transpose() * result->estimate.T_prev_cur.linear()).norm(), 1e-2);  // E is not refined.
}

// One camera: the essential matrix and the rotation homography run OpenCV's RANSAC on the
// correspondences in the order of options.ransac_order_seed; their inlier flags come back in the
// caller's order for every seed.
TEST(MotionEstimator, OneCameraInliersAreInTheCallersOrderForEveryOrderSeed) {
  std::mt19937 rng(9);
  const StereoRig rig = TestRig();
  const auto matches = MakeCorrespondences(rig, TestMotion(), 200, 0.3, 0.0, &rng);
  std::vector<Eigen::Vector2d> uv_prev, uv_cur, uv_rotated;
  const Pose rotation =
      MakePose(ExpSO3(Eigen::Vector3d(0.01, 0.04, -0.02)), Eigen::Vector3d::Zero());
  for (const auto& m : matches) {
    Eigen::Vector2d uv, uv_r;
    ASSERT_TRUE(rig.left.Project(m.p_prev, &uv));
    ASSERT_TRUE(rig.left.Project(rotation.inverse() * m.p_prev, &uv_r));
    uv_prev.push_back(uv);
    uv_cur.push_back(m.uv_cur);
    uv_rotated.push_back(uv_r);
  }
  for (size_t i = 0; i < uv_cur.size(); i += 4) {  // Every fourth correspondence is wrong.
    uv_cur[i] += Eigen::Vector2d(35, -20);
    uv_rotated[i] += Eigen::Vector2d(35, -20);
  }
  for (const uint64_t order_seed : {0u, 1u, 5u}) {
    SCOPED_TRACE(order_seed);
    MotionEstimatorOptions options;
    options.ransac_order_seed = order_seed;
    MotionEstimator estimator(rig, options);
    for (const auto* cur : {&uv_cur, &uv_rotated}) {
      const auto result = cur == &uv_cur ? estimator.EstimateEssential(uv_prev, *cur)
                                         : estimator.EstimateRotation(uv_prev, *cur);
      ASSERT_TRUE(result.has_value());
      ASSERT_EQ(result->inlier.size(), uv_prev.size());
      int wrong_kept = 0, right_kept = 0;
      for (size_t i = 0; i < uv_prev.size(); ++i) {
        (i % 4 == 0 ? wrong_kept : right_kept) += result->inlier[i];
      }
      // A wrong correspondence moved along its epipolar line can pass; flags in another order
      // would keep about as many of the 50 wrong ones as of the 150 right ones.
      EXPECT_LE(wrong_kept, 5);
      EXPECT_GT(right_kept, 110);
    }
  }
}

}  // namespace
}  // namespace dala
