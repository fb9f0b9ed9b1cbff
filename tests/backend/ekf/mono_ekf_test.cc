#include "backend/ekf/mono_ekf.h"

#include <glog/logging.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/eval/evaluate.h"
#include "tests/backend/ekf/measurement_simulator.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::SimOptions;
using testing::SimPath;
using testing::SimStream;
using testing::Simulate;

double AteRmse(const Trajectory& gt, const Trajectory& est) {
  EvalOptions options;
  options.kitti_segments = false;
  const EvalResult r = Evaluate(gt, est, options);
  CHECK(r.ok) << r.error;
  return r.ate.translation.rmse;
}

TEST(MonoEkfTest, GaussianSumIsTheGeometricSeries) {
  MonoEkfOptions o;
  const auto depths = GaussianSumDepths(o);
  const double beta = (1 + o.alpha * o.k_sigma) / (1 - o.alpha * o.k_sigma);
  ASSERT_GE(depths.size(), 3u);
  EXPECT_NEAR(depths[0].first, o.d_min / (1 + o.alpha), 1e-12);
  for (size_t i = 0; i < depths.size(); ++i) {
    EXPECT_NEAR(depths[i].second, o.alpha * depths[i].first, 1e-12);
    if (i > 0) {
      EXPECT_NEAR(depths[i].first, beta * depths[i - 1].first, 1e-9);
    }
    // Only the last one reaches d_max.
    EXPECT_EQ(depths[i].first + depths[i].second >= o.d_max, i + 1 == depths.size());
  }
  EXPECT_EQ(depths.size(), 12u);  // 0.5 .. 100 m with alpha 0.25, k_sigma 1.
}

// Landmarks at 2, 10 and 50 m straight ahead, the camera translating sideways with accurate
// odometry: the Gaussian sum must select the right depth and the EKF refine it.
TEST(MonoEkfTest, GaussianSumConvergesToTrueDepth) {
  SimOptions o;
  o.path = SimPath::kLateral;
  o.stereo = false;
  o.fill_odometry = true;
  o.frames = 100;
  o.speed = 0.1;
  o.sigma_px = 0.5;
  o.motion_sigma_rot = 1e-4;
  o.motion_sigma_trans = 1e-3;
  const double depths[3] = {2.0, 10.0, 50.0};
  const double x0[3] = {1.2, 5.0, 5.0};  // Stay in view over most of the 10 m travel.
  for (int k = 0; k < 3; ++k) o.points_w.push_back(Eigen::Vector3d(x0[k], 0.2 * k, depths[k]));
  // Some background points for the filter (ids 3..).
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 40; ++k) {
    o.points_w.push_back(Eigen::Vector3d(5 + 8 * u(rng), 2 * u(rng), 12 + 6 * u(rng)));
  }
  const SimStream s = Simulate(o);
  MonoEkfEstimator ekf(s.rig.left);
  int inserted_frame[3] = {-1, -1, -1};
  for (const FrameMeasurement& m : s.frames) {
    ekf.Add(m);
    for (int k = 0; k < 3; ++k) {
      if (inserted_frame[k] < 0 && ekf.state().IndexOf(LandmarkId(k)) >= 0) {
        inserted_frame[k] = static_cast<int>(m.frame.value);
      }
    }
  }
  for (int k = 0; k < 3; ++k) {
    const int i = ekf.state().IndexOf(LandmarkId(k));
    ASSERT_GE(i, 0) << "landmark at " << depths[k] << " m not initialised";
    const Eigen::Vector3d err = ekf.state().p_w(i) - o.points_w[k];
    const double sigma_z = std::sqrt(ekf.state().landmark_covariance(i)(2, 2));
    std::printf("depth %.0f m: inserted at frame %d, error %.3f m (%.2f %%), final sigma %.3f m\n",
                depths[k], inserted_frame[k], err.z(), 100 * std::abs(err.z()) / depths[k],
                sigma_z);
    EXPECT_LT(std::abs(err.z()), 3 * sigma_z);
    EXPECT_LT(std::abs(err.z()), 0.03 * depths[k]);
  }
  for (int k = 0; k < 3; ++k) EXPECT_LT(inserted_frame[k], 40);
}

TEST(MonoEkfTest, TracksACurvedPathWithOdometryAndReportsNees) {
  const int runs = 20, frames = 60;
  std::vector<double> nees_sum(frames, 0.0);
  double ate_sum = 0, ate_dr_sum = 0;
  double rot_sum = 0, rot_dr_sum = 0;  // Mean rotation error (deg) over the frames.
  int max_state = 0;
  for (int run = 0; run < runs; ++run) {
    SimOptions o;
    o.frames = frames;
    o.stereo = false;
    o.fill_odometry = true;
    o.num_points = 500;
    o.motion_sigma_rot = 0.003;
    o.motion_sigma_trans = 0.015;
    o.seed = 300 + run;
    const SimStream s = Simulate(o);
    MonoEkfEstimator ekf(s.rig.left);
    for (int i = 0; i < frames; ++i) {
      const EstimatorOutput out = ekf.Add(s.frames[i]);
      EXPECT_TRUE(out.valid);
      max_state = std::max(max_state, out.landmarks_in_state);
      if (i == 0) continue;
      const Vector6d e = LogSE3(ekf.state().T_w_c().inverse() * s.T_w_c_gt[i]);
      nees_sum[i] += e.dot(ekf.pose_covariance().ldlt().solve(e));
    }
    ate_sum += AteRmse(s.gt, ekf.trajectory()) / runs;
    ate_dr_sum += AteRmse(s.gt, s.dead_reckoning) / runs;
    const Trajectory filtered = ekf.trajectory();
    ASSERT_EQ(filtered.poses.size(), static_cast<size_t>(frames));
    ASSERT_EQ(s.dead_reckoning.poses.size(), static_cast<size_t>(frames));
    for (int i = 0; i < frames; ++i) {
      const auto angle_deg = [&](const Pose& T_w_c) {
        return Eigen::AngleAxisd(T_w_c.linear().transpose() * s.T_w_c_gt[i].linear()).angle() *
               180.0 / M_PI;
      };
      rot_sum += angle_deg(filtered.poses[i].T_w_c) / (runs * frames);
      rot_dr_sum += angle_deg(s.dead_reckoning.poses[i].T_w_c) / (runs * frames);
    }
  }
  double mean = 0;
  std::printf("mono EKF average pose NEES per frame (6 dof; consistent ~6):\n");
  for (int i = 1; i < frames; ++i) {
    mean += nees_sum[i] / runs / (frames - 1);
    std::printf("%.2f%s", nees_sum[i] / runs, i % 15 == 0 ? "\n" : " ");
  }
  std::printf(
      "\nmean NEES %.2f; mean ATE %.4f m vs dead reckoning %.4f m; rotation error %.3f deg vs "
      "%.3f deg; max state %d\n",
      mean, ate_sum, ate_dr_sum, rot_sum, rot_dr_sum, max_state);
  EXPECT_GT(max_state, 20);
  // What the map adds to the odometry: the orientation (the bearings of landmarks seen from many
  // frames hold it); the scale and the translation drift come from the odometry, so the
  // translation may not beat it (measured 0.0632 m vs 0.0627 m). Measured mean rotation error
  // 0.426 deg against the dead reckoning's 1.366 deg. Bounds: 1.5x the measured value, and at
  // most half the dead reckoning's.
  testing::ExpectWithinBound("ekf/mono with odometry, 20 curved runs, mean rotation error", rot_sum,
                             0.426, "deg");
  EXPECT_LT(rot_sum, 0.5 * rot_dr_sum);
  EXPECT_LT(ate_sum, 1.05 * ate_dr_sum);
  // Mildly overconfident (docs/ekf.md): measured mean 8.05, per frame 5.2 .. 9.8, above the 95 %
  // band of 20 runs (4.6 .. 7.6) from frame 5 on. With the classic error state it diverged (mean
  // 242, ~370 at frame 60). This bounds the measured state.
  EXPECT_LT(mean, 9.0);
  for (int i = 1; i < frames; ++i) EXPECT_LT(nees_sum[i] / runs, 11.0) << "frame " << i;
}

TEST(MonoEkfTest, NoScaleMeansNoPrediction) {
  SimOptions o;
  o.frames = 5;
  o.stereo = false;
  SimStream s = Simulate(o);
  // The paper's model ("motion"): "auto" would take the constant-velocity model at frame 1,
  // which has no metric motion.
  MonoEkfOptions options;
  options.prediction = "motion";
  MonoEkfEstimator ekf(s.rig.left, options);
  EXPECT_TRUE(ekf.Add(s.frames[0]).valid);
  FrameMeasurement m = s.frames[1];
  m.motion->scale_known = false;  // Monocular visual motion: unit translation.
  const EstimatorOutput out = ekf.Add(m);
  EXPECT_FALSE(out.valid);
  EXPECT_POSE_NEAR(out.T_w_c, Pose::Identity(), 1e-12);
  // Scale-known motion is used as dead reckoning when there is no odometry.
  const EstimatorOutput out2 = ekf.Add(s.frames[2]);
  EXPECT_TRUE(out2.valid);
  EXPECT_GT(out2.T_w_c.translation().norm(), 0.1);
}

TEST(MonoEkfTest, DeterministicAndBounded) {
  SimOptions o;
  o.frames = 50;
  o.stereo = false;
  o.fill_odometry = true;
  const SimStream s = Simulate(o);
  MonoEkfOptions options;
  options.max_landmarks = 25;
  MonoEkfEstimator a(s.rig.left, options), b(s.rig.left, options);
  for (const FrameMeasurement& m : s.frames) {
    EXPECT_LE(a.Add(m).landmarks_in_state, 25);
    b.Add(m);
    EXPECT_LE(a.last_stats().candidates, options.max_candidates);
  }
  EXPECT_EQ(a.state().num_landmarks(), 25);
  for (size_t i = 0; i < s.frames.size(); ++i) {
    EXPECT_EQ(a.trajectory().poses[i].T_w_c.matrix(), b.trajectory().poses[i].T_w_c.matrix());
  }
}

TEST(MonoEkfTest, InvalidOptionsAreReported) {
  MonoEkfOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.alpha = 2.0;  // alpha * k_sigma >= 1: beta undefined.
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("alpha"), std::string::npos);
}

}  // namespace
}  // namespace dala
