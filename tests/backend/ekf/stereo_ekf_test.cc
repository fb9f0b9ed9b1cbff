#include "backend/ekf/stereo_ekf.h"

#include <glog/logging.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>

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

// Wilson-Hilferty approximation of the chi-square quantile (accurate to <1 % for k >= 30).
double Chi2Quantile(double z_p, double k) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z_p * std::sqrt(a), 3);
}

TEST(StereoEkfTest, BeatsDeadReckoningOnCurvedPath) {
  SimOptions o;
  o.frames = 150;
  o.sigma_px = 0.7;
  o.motion_sigma_rot = 0.003;
  o.motion_sigma_trans = 0.015;
  const SimStream s = Simulate(o);
  StereoEkfEstimator ekf(s.rig);
  int max_state = 0;
  for (const FrameMeasurement& m : s.frames) {
    const EstimatorOutput out = ekf.Add(m);
    EXPECT_TRUE(out.valid);
    max_state = std::max(max_state, out.landmarks_in_state);
  }
  ASSERT_EQ(ekf.trajectory().size(), s.frames.size());
  const double ate = AteRmse(s.gt, ekf.trajectory());
  const double ate_dr = AteRmse(s.gt, s.dead_reckoning);
  std::printf("stereo EKF ATE %.4f m, dead reckoning %.4f m, path %.1f m, max state %d\n", ate,
              ate_dr, s.gt.PathLength(), max_state);
  EXPECT_LT(ate, 0.7 * ate_dr);
  testing::ExpectWithinBound("ekf/stereo curved path of 44.7 m (geometric scene), ATE", ate, 0.0124,
                             "m");
  EXPECT_LE(max_state, StereoEkfOptions().max_landmarks);
  EXPECT_GT(max_state, 30);
}

// Average pose NEES per frame over seeded Monte Carlo runs (40 frames, 400 points, curved path)
// and its 95 % band: for r runs, r * NEES ~ chi2(6 r).
struct NeesCurve {
  std::vector<double> nees;  // Frames 1..; frame 0 is the world frame (zero covariance).
  double lo = 0, hi = 0, mean = 0;
  int outside = 0;
};

NeesCurve MonteCarloPoseNees(int runs, int frames, bool motion_from_stereo_points,
                             const StereoEkfOptions& options = {}) {
  std::vector<double> nees_sum(frames, 0.0);
  for (int run = 0; run < runs; ++run) {
    SimOptions o;
    o.frames = frames;
    o.num_points = 400;
    o.seed = 100 + run;
    o.motion_from_stereo_points = motion_from_stereo_points;
    const SimStream s = Simulate(o);
    StereoEkfEstimator ekf(s.rig, options);
    for (int i = 0; i < frames; ++i) {
      ekf.Add(s.frames[i]);
      if (i == 0) continue;
      const Vector6d e = LogSE3(ekf.state().T_w_c().inverse() * s.T_w_c_gt[i]);
      nees_sum[i] += e.dot(ekf.pose_covariance().ldlt().solve(e));
    }
  }
  NeesCurve c;
  c.lo = Chi2Quantile(-1.959964, 6.0 * runs) / runs;
  c.hi = Chi2Quantile(1.959964, 6.0 * runs) / runs;
  for (int i = 1; i < frames; ++i) {
    const double nees = nees_sum[i] / runs;
    c.nees.push_back(nees);
    c.mean += nees / (frames - 1);
    if (nees < c.lo || nees > c.hi) ++c.outside;
  }
  return c;
}

void PrintNees(const char* what, const NeesCurve& c) {
  std::printf("%s: average pose NEES per frame (95%% band %.2f..%.2f):\n", what, c.lo, c.hi);
  for (size_t i = 0; i < c.nees.size(); ++i) {
    std::printf("%.2f%s", c.nees[i], (i + 1) % 13 == 0 ? "\n" : " ");
  }
  std::printf("mean %.2f, %d of %zu frames outside\n", c.mean, c.outside, c.nees.size());
}

TEST(StereoEkfTest, PoseNeesIsConsistentOverMonteCarloRuns) {
  // Motion noise independent of the image noise, with its exact covariance: no inflation.
  StereoEkfOptions options;
  options.motion_covariance_scale = 1.0;
  const NeesCurve c = MonteCarloPoseNees(25, 40, false, options);
  PrintNees("stereo EKF, independent motion noise", c);
  // docs/ekf.md. With the classic error state (docs/ekf.md) the mean is 6.87 and 11 of 39
  // frames are above the band, growing with time (spurious information on the unobservable
  // directions).
  EXPECT_LE(c.outside, 4);  // About 10 %; 5 % expected by chance.
  EXPECT_GT(c.mean, c.lo);
  EXPECT_LT(c.mean, c.hi);
}

// A real frontend's motion comes from the same stereo points that update the filter. The motion
// estimate alone is consistent (its NEES against the true motion is ~6), but used as the
// prediction its information is counted twice: the filter is overconfident unless the motion
// covariance is inflated (StereoEkfOptions::motion_covariance_scale x3; docs/ekf.md).
TEST(StereoEkfTest, PoseNeesWithMotionFromTheSameStereoPoints) {
  // The motion estimate against the truth.
  double motion_nees = 0;
  int motions = 0;
  for (int run = 0; run < 5; ++run) {
    SimOptions o;
    o.frames = 40;
    o.num_points = 400;
    o.seed = 100 + run;
    o.motion_from_stereo_points = true;
    const SimStream s = Simulate(o);
    for (int i = 1; i < o.frames; ++i) {
      const Pose M_true = s.T_w_c_gt[i - 1].inverse() * s.T_w_c_gt[i];
      const Vector6d e = LogSE3(s.frames[i].motion->T_prev_cur.inverse() * M_true);
      motion_nees += e.dot(s.frames[i].motion->cov.ldlt().solve(e));
      ++motions;
    }
  }
  motion_nees /= motions;
  std::printf("motion from stereo points: NEES %.2f over %d motions\n", motion_nees, motions);
  const double lo = Chi2Quantile(-2.575829, 6.0 * motions) / motions;
  const double hi = Chi2Quantile(2.575829, 6.0 * motions) / motions;
  EXPECT_GT(motion_nees, lo);
  EXPECT_LT(motion_nees, hi);

  StereoEkfOptions counted_twice;
  counted_twice.motion_covariance_scale = 1.0;
  const NeesCurve c1 = MonteCarloPoseNees(25, 40, true, counted_twice);
  PrintNees("stereo EKF, motion from the same points, motion covariance as is", c1);
  StereoEkfOptions inflated;
  inflated.motion_covariance_scale = 3.0;
  const NeesCurve c3 = MonteCarloPoseNees(25, 40, true, inflated);
  PrintNees("stereo EKF, motion from the same points, motion covariance x3", c3);
  // Measured: mean 10.7 (37 of 39 frames above the band) as is; 6.43 (2 outside) with x3.
  EXPECT_GT(c1.mean, c1.hi);
  EXPECT_GT(c3.mean, c3.lo);
  EXPECT_LT(c3.mean, c3.hi);
  EXPECT_LE(c3.outside, 4);
}

TEST(StereoEkfTest, MapIsBoundedAndSpreadOverZones) {
  SimOptions o;
  o.frames = 60;
  o.num_points = 1500;
  const SimStream s = Simulate(o);
  StereoEkfOptions options;
  options.max_landmarks = 60;
  StereoEkfEstimator ekf(s.rig, options);
  int evictions = 0;
  for (const FrameMeasurement& m : s.frames) {
    const EstimatorOutput out = ekf.Add(m);
    EXPECT_LE(out.landmarks_in_state, 60);
    evictions += ekf.last_stats().removed;
    if (m.frame.value == 0) {
      // First frame: every zone with candidates gets min(2, target) new landmarks.
      std::set<int> zones;
      for (const MapPoint& p : ekf.map()) {
        Eigen::Vector2d uv;
        ASSERT_TRUE(s.rig.left.Project(p.p_w, &uv));
        zones.insert(static_cast<int>(uv.y() / 120) * 4 + static_cast<int>(uv.x() / 160));
      }
      EXPECT_GE(zones.size(), 14u);
      EXPECT_LE(ekf.map().size(), 32u);
    }
  }
  EXPECT_EQ(ekf.state().num_landmarks(), 60);
  EXPECT_GT(evictions, 10);  // The bounded state made room for new landmarks.
  EXPECT_LT(AteRmse(s.gt, ekf.trajectory()), 0.1);
}

TEST(StereoEkfTest, RemovesLandmarksThatFailGating) {
  SimOptions o;
  o.frames = 30;
  o.num_points = 600;
  SimStream s = Simulate(o);
  StereoEkfEstimator ekf(s.rig);
  ekf.Add(s.frames[0]);
  ASSERT_GT(ekf.state().num_landmarks(), 0);
  // A state landmark still tracked in the next 4 frames.
  LandmarkId bad;
  for (int i = 0; i < ekf.state().num_landmarks() && !bad.valid(); ++i) {
    int seen = 0;
    for (int k = 1; k <= 4; ++k) {
      for (const FeatureObservation& obs : s.frames[k].observations) {
        seen += obs.landmark == ekf.state().id(i);
      }
    }
    if (seen == 4) bad = ekf.state().id(i);
  }
  ASSERT_TRUE(bad.valid());
  int frames_with_bad = 0;
  for (size_t i = 1; i < s.frames.size(); ++i) {
    FrameMeasurement m = s.frames[i];
    for (FeatureObservation& obs : m.observations) {
      if (obs.landmark == bad) {
        obs.uv.y() += 40.0;  // A mismatch: 40 px off.
        ++frames_with_bad;
      }
    }
    ekf.Add(m);
    if (frames_with_bad >= 3) break;
  }
  ASSERT_GE(frames_with_bad, 3) << "the landmark left the view too early";
  EXPECT_EQ(ekf.state().IndexOf(bad), -1);
}

TEST(StereoEkfTest, LostFramesInflateCovarianceAndAreInvalid) {
  SimOptions o;
  o.frames = 30;
  o.lost_frames = {10, 11};
  SimStream s = Simulate(o);
  s.frames[10].observations.clear();  // Nothing at all at frame 10: the pose must be kept.
  StereoEkfOptions options;
  StereoEkfEstimator ekf(s.rig, options);
  for (int i = 0; i < o.frames; ++i) {
    const Pose T_before = ekf.state().T_w_c();
    const double trace_before = ekf.pose_covariance().trace();
    const EstimatorOutput out = ekf.Add(s.frames[i]);
    if (i == 10) {
      EXPECT_FALSE(out.valid);
      EXPECT_POSE_NEAR(out.T_w_c, T_before, 1e-12);
      const double r2 = std::pow(options.lost_rotation_sigma, 2);
      const double t2 = std::pow(options.lost_translation_sigma, 2);
      EXPECT_NEAR(ekf.pose_covariance().trace() - trace_before, 3 * (r2 + t2), 1e-9);
    } else if (i == 11) {
      EXPECT_FALSE(out.valid);  // Relocalised by the map, but reported as not tracked.
    } else {
      EXPECT_TRUE(out.valid);
    }
  }
  // The map relocalises the camera after the gap: kept through 2 frames of 0.3 m, the pose would
  // be 0.6 m off at frame 11 (measured: 0.23 m at frame 11, 0.18 m at the end; a single EKF
  // update from a 0.6 m prior error does not relocalise fully, see docs/ekf.md).
  const auto& est = ekf.trajectory().poses;
  EXPECT_LT((est[11].T_w_c.translation() - s.T_w_c_gt[11].translation()).norm(), 0.3);
  EXPECT_LT((est.back().T_w_c.translation() - s.T_w_c_gt.back().translation()).norm(), 0.3);
}

// 1.2 turns of a 10 m circle among points 3-10 m away: the camera comes back at frame 125.
SimOptions CircleLoopOptions() {
  SimOptions o;
  o.path = SimPath::kCircle;
  o.frames = 150;
  o.turns = 1.2;
  o.radius = 10.0;
  o.num_points = 300;
  o.point_min_depth = 3;
  o.point_max_depth = 10;
  o.sigma_px = 1.0;
  o.motion_sigma_rot = 0.01;
  o.motion_sigma_trans = 0.05;
  return o;
}

TEST(StereoEkfTest, ReobservingOldLandmarksClosesTheLoop) {
  SimOptions o = CircleLoopOptions();
  double ate[2];
  int loops[2] = {0, 0};
  for (int persistent = 0; persistent < 2; ++persistent) {
    o.persistent_ids = persistent == 1;
    const SimStream s = Simulate(o);
    StereoEkfOptions options;
    options.max_landmarks = 150;
    StereoEkfEstimator ekf(s.rig, options);
    for (const FrameMeasurement& m : s.frames) loops[persistent] += ekf.Add(m).loop_closed;
    ate[persistent] = AteRmse(s.gt, ekf.trajectory());
    // After the loop, the end pose is much better with the re-identified landmarks.
  }
  std::printf("circle: ATE without loop ids %.3f m, with %.3f m; loop frames %d\n", ate[0], ate[1],
              loops[1]);
  EXPECT_EQ(loops[0], 0);
  EXPECT_GT(loops[1], 0);
  EXPECT_LT(ate[1], ate[0]);
}

// The frontend's loop closing (LoopDetection): on a circle, the tracker gives new ids when the
// camera comes back, and at frame kLoop the recognised place relabels the current observations
// with the ids of the first frames. The filter, which kept those landmarks, re-observes them: the
// pose error must drop at the loop frame and the NEES stay consistent afterwards.
TEST(StereoEkfTest, LoopDetectionRelabellingCorrectsTheDrift) {
  constexpr int kLoop = 126;  // The circle closes at frame 125 (1.2 turns over 150 frames).
  const int seeds = 3;
  double err_before_sum = 0, err_after_sum = 0, nees_after_sum = 0, ate_sum[2] = {0, 0};
  int nees_count = 0, loop_updates = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    for (int with_loop = 0; with_loop < 2; ++with_loop) {
      SimOptions o = CircleLoopOptions();
      o.seed = 300 + seed;
      o.loop_frame = with_loop ? kLoop : -1;
      o.loop_old_frames = 10;
      const SimStream s = Simulate(o);
      if (with_loop) {
        ASSERT_TRUE(s.frames[kLoop].loop.has_value());
        ASSERT_GT(s.frames[kLoop].loop->relabelled.size(), 10u);
      }
      StereoEkfOptions options;               // Default map management: 300 landmarks at most.
      options.motion_covariance_scale = 1.0;  // Independent motion noise, exact covariance.
      StereoEkfEstimator ekf(s.rig, options);
      for (int i = 0; i < o.frames; ++i) {
        const EstimatorOutput out = ekf.Add(s.frames[i]);
        EXPECT_EQ(out.loop_closed, with_loop == 1 && i == kLoop) << "frame " << i;
        if (!with_loop) continue;
        const double err = (out.T_w_c.translation() - s.T_w_c_gt[i].translation()).norm();
        if (i == kLoop - 1) err_before_sum += err;
        if (i == kLoop) {
          err_after_sum += err;
          loop_updates += ekf.last_stats().loop_updates;
        }
        if (i >= kLoop) {
          const Vector6d e = LogSE3(ekf.state().T_w_c().inverse() * s.T_w_c_gt[i]);
          nees_after_sum += e.dot(ekf.pose_covariance().ldlt().solve(e));
          ++nees_count;
        }
      }
      ate_sum[with_loop] += AteRmse(s.gt, ekf.trajectory());
    }
  }
  const double nees_after = nees_after_sum / nees_count;
  std::printf(
      "loop (%d seeds): position error %.3f m before the loop frame, %.3f m at it (%.1f loop "
      "updates per run); ATE %.3f m without loop, %.3f m with; NEES after the loop %.2f\n",
      seeds, err_before_sum / seeds, err_after_sum / seeds, double(loop_updates) / seeds,
      ate_sum[0] / seeds, ate_sum[1] / seeds, nees_after);
  EXPECT_LT(err_after_sum, 0.5 * err_before_sum);
  EXPECT_LT(ate_sum[1], ate_sum[0]);
  EXPECT_GT(loop_updates, 10 * seeds);
  // Pose NEES (6 dof) averaged over the 24 frames after the loop and the seeds. The frames of one
  // run are strongly correlated, so the honest reference is the 99 % bound of a 3-run average of
  // chi2(6), 11.6 (measured: 7.9 with 3 seeds, 6.8 with 5; a broken loop update gives hundreds).
  EXPECT_LT(nees_after, 11.6);
}

TEST(StereoEkfTest, Deterministic) {
  SimOptions o;
  o.frames = 40;
  const SimStream s = Simulate(o);
  StereoEkfEstimator a(s.rig), b(s.rig);
  for (const FrameMeasurement& m : s.frames) {
    a.Add(m);
    b.Add(m);
  }
  for (size_t i = 0; i < s.frames.size(); ++i) {
    EXPECT_EQ(a.trajectory().poses[i].T_w_c.matrix(), b.trajectory().poses[i].T_w_c.matrix());
  }
  EXPECT_EQ(a.state().covariance(), b.state().covariance());
}

TEST(StereoEkfTest, InvalidOptionsAreReported) {
  StereoEkfOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.max_landmarks = 0;
  o.gate_chi2 = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_landmarks"), std::string::npos);
  EXPECT_NE(why.find("gate_chi2"), std::string::npos);
}

}  // namespace
}  // namespace dala
