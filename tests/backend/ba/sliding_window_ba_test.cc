#include "backend/ba/sliding_window_ba.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "tests/backend/ba/ba_synthetic_scene.h"
#include "tests/backend/ba/window_keyframe_poses.h"

namespace dala {
namespace {

using testing::AlignedAte;
using testing::AllKeyframePoses;
using testing::BaScene;
using testing::BaSceneOptions;
using testing::MakeBaScene;
using testing::PerturbPose;

// Initial guesses as a visual odometry would give them: noisy relative motions chained on the
// previous estimate (so they drift).
std::vector<Pose> NoisyRelativeMotions(const BaScene& scene, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Pose> T_prev_cur(scene.T_w_c_gt.size(), Pose::Identity());
  for (size_t i = 1; i < scene.T_w_c_gt.size(); ++i) {
    T_prev_cur[i] =
        PerturbPose(scene.T_w_c_gt[i - 1].inverse() * scene.T_w_c_gt[i], rng, 0.005, 0.03);
  }
  return T_prev_cur;
}

// Feeds the scene keyframe by keyframe, optimising after each one (the online use).
std::vector<Pose> RunSequential(const BaScene& scene, const SlidingWindowBa::Options& options,
                                unsigned seed, SlidingWindowBa* ba_out = nullptr) {
  SlidingWindowBa local(scene.K, options);
  SlidingWindowBa& ba = ba_out ? *ba_out : local;
  const auto T_prev_cur = NoisyRelativeMotions(scene, seed);
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    kf.T_w_c =
        i == 0 ? scene.T_w_c_gt[0] : *ba.KeyframePose(scene.keyframes[i - 1].id) * T_prev_cur[i];
    ba.AddKeyframe(kf);
    const auto s = ba.Optimize();
    EXPECT_TRUE(s.usable) << s.BriefReport();
  }
  return AllKeyframePoses(ba);
}

// All keyframes in one window, initialised by chaining the noisy relative motions.
std::vector<Pose> RunBatch(const BaScene& scene, SlidingWindowBa::Options options, unsigned seed,
                           SlidingWindowBa::Summary* summary = nullptr) {
  options.window_size = static_cast<int>(scene.keyframes.size());
  options.max_num_iterations = 50;
  SlidingWindowBa ba(scene.K, options);
  const auto T_prev_cur = NoisyRelativeMotions(scene, seed);
  Pose T_w_c = scene.T_w_c_gt[0];
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    if (i > 0) T_w_c = T_w_c * T_prev_cur[i];
    kf.T_w_c = T_w_c;
    ba.AddKeyframe(kf);
  }
  const auto s = ba.Optimize();
  EXPECT_TRUE(s.usable) << s.BriefReport();
  if (summary) *summary = s;
  return AllKeyframePoses(ba);
}

BaSceneOptions SmallScene() {
  BaSceneOptions o;
  o.num_keyframes = 24;
  o.num_points = 300;
  o.pixel_noise = 0.5;
  return o;
}

// One camera, 12 keyframes: the landmarks must be given positions (SeedLandmarks), as the
// two-view initialisation does in a run.
BaSceneOptions MonoScene() {
  BaSceneOptions o = SmallScene();
  o.stereo = false;
  o.num_keyframes = 12;
  return o;
}

// Every landmark at its true position plus N(0, sigma^2) per axis.
void SeedLandmarks(const BaScene& scene, double sigma, std::mt19937* rng, SlidingWindowBa* ba) {
  std::normal_distribution<double> n(0.0, sigma);
  for (size_t j = 0; j < scene.p_w_gt.size(); ++j) {
    Eigen::Vector3d noise;
    for (int k = 0; k < 3; ++k) noise[k] = n(*rng);  // In order (argument order is unspecified).
    ba->SetLandmarkPosition(LandmarkId(static_cast<int64_t>(j)), scene.p_w_gt[j] + noise);
  }
}

std::vector<Pose> ChainedInitialGuess(const BaScene& scene, unsigned seed) {
  const auto T_prev_cur = NoisyRelativeMotions(scene, seed);
  std::vector<Pose> init{scene.T_w_c_gt[0]};
  for (size_t i = 1; i < scene.T_w_c_gt.size(); ++i) init.push_back(init.back() * T_prev_cur[i]);
  return init;
}

TEST(SlidingWindowBaTest, BatchStereoConverges) {
  const BaScene scene = MakeBaScene(SmallScene());
  SlidingWindowBa::Summary summary;
  const auto est = RunBatch(scene, SlidingWindowBa::Options(), 7, &summary);
  const double ate_init = AlignedAte(ChainedInitialGuess(scene, 7), scene.T_w_c_gt);
  const double ate = AlignedAte(est, scene.T_w_c_gt);
  EXPECT_GT(ate_init, 0.05);
  EXPECT_LT(ate, 0.01) << summary.BriefReport();
  EXPECT_LT(summary.final_cost, 0.2 * summary.initial_cost);
  EXPECT_EQ(summary.num_keyframes, 24);
}

TEST(SlidingWindowBaTest, WindowWithPriorStaysCloseToBatch) {
  const BaScene scene = MakeBaScene(SmallScene());
  SlidingWindowBa::Options options;
  const double ate_batch = AlignedAte(RunBatch(scene, options, 7), scene.T_w_c_gt);
  SlidingWindowBa ba(scene.K, options);
  const double ate_window = AlignedAte(RunSequential(scene, options, 7, &ba), scene.T_w_c_gt);
  EXPECT_LT(ate_window, 2.0 * ate_batch + 0.005) << "batch " << ate_batch;
  // The gauge keyframe (0) left long ago: the prior, relative to it, has full rank on the 7
  // remaining older poses, and the window's ABSOLUTE error stays small.
  EXPECT_EQ(ba.prior().rank(), 6 * (options.window_size - 1));
  for (KeyframeId id : ba.WindowKeyframes()) {
    const Pose& gt = scene.T_w_c_gt[id.value];
    EXPECT_LT((ba.KeyframePose(id)->translation() - gt.translation()).norm(), 0.05);
  }
  // Ablation: the same window with the prior discarded (the oldest keyframe held constant for
  // the gauge instead) is clearly worse: the prior carries the old information. (Measured over
  // 6 scene seeds the ratio was 0.65..0.89; here 0.66.)
  options.keep_prior = false;
  const double ate_ablation = AlignedAte(RunSequential(scene, options, 7), scene.T_w_c_gt);
  EXPECT_LT(ate_window, 0.85 * ate_ablation) << "ablation " << ate_ablation;
  RecordProperty("ate_batch_mm", std::to_string(ate_batch * 1e3));
  RecordProperty("ate_window_mm", std::to_string(ate_window * 1e3));
  RecordProperty("ate_no_prior_mm", std::to_string(ate_ablation * 1e3));
}

// The default exit of sequences (SequenceBaOptions): landmarks that keep >= 2 observations stay
// in the window, the others are marginalised into the prior. Close to the batch solution, and
// not worse than the same window with its prior discarded.
TEST(SlidingWindowBaTest, DropSharedObservationsWindowStaysCloseToBatch) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    BaSceneOptions so = SmallScene();
    so.seed = seed;
    const BaScene scene = MakeBaScene(so);
    SlidingWindowBa::Options options;
    options.landmark_exit = SlidingWindowBa::LandmarkExit::kDropSharedObservations;
    const double ate_batch = AlignedAte(RunBatch(scene, options, 7), scene.T_w_c_gt);
    const double ate_window = AlignedAte(RunSequential(scene, options, 7), scene.T_w_c_gt);
    options.keep_prior = false;
    const double ate_ablation = AlignedAte(RunSequential(scene, options, 7), scene.T_w_c_gt);
    std::cout << "[ measured ] seed " << seed << ": batch " << ate_batch << ", window "
              << ate_window << ", prior discarded " << ate_ablation << " m" << std::endl;
    EXPECT_LT(ate_window, 2.0 * ate_batch + 0.005) << "seed " << seed;
    EXPECT_LE(ate_window, 1.05 * ate_ablation) << "seed " << seed;
  }
}

// Regression (issue 4, rover loop ATE 1.1-5.5 m with the prior): on a long run the prior's
// information on the ABSOLUTE pose of the window decays until its gauge directions fall below the
// eigenvalue floor (rover loop: after ~250 keyframes). When the prior was left to hold the gauge,
// the window then moved freely as a rigid body (3.5 deg, 2.9 m in one solve). A higher floor
// puts this short scene in that state from the start; the window must still stay put because
// its oldest keyframe holds the gauge. (Measured: 2.3 m maximum error with the old gauge handling,
// 2 cm now.)
TEST(SlidingWindowBaTest, WindowDoesNotDriftWhenThePriorLosesItsGaugeDirections) {
  BaSceneOptions so;
  so.num_keyframes = 30;
  so.num_points = 400;
  so.seed = 3;
  const BaScene scene = MakeBaScene(so);
  SlidingWindowBa::Options options;
  options.prior_eigenvalue_floor = 1e-5;
  SlidingWindowBa ba(scene.K, options);
  const auto est = RunSequential(scene, options, 5, &ba);
  // The scenario: the prior has lost directions (the gauge, as on the long run).
  EXPECT_LT(ba.prior().rank(), 6 * (options.window_size - 1));
  double max_err = 0.0;
  for (size_t i = 0; i < est.size(); ++i) {
    max_err = std::max(max_err, (est[i].translation() - scene.T_w_c_gt[i].translation()).norm());
  }
  EXPECT_LT(max_err, 0.05);  // no alignment: keyframe 0 is held at the truth.
  RecordProperty("max_error_mm", std::to_string(max_err * 1e3));
}

TEST(SlidingWindowBaTest, TrackFrameAgainstTheWindowMap) {
  BaSceneOptions so = SmallScene();
  so.num_keyframes = 10;
  const BaScene scene = MakeBaScene(so);
  SlidingWindowBa ba(scene.K, SlidingWindowBa::Options());
  RunSequential(scene, SlidingWindowBa::Options(), 3, &ba);
  // A frame at keyframe 9's place, seen with fresh noise, tracked from a perturbed guess.
  std::mt19937 rng(8);
  const Pose& gt = scene.T_w_c_gt[9];
  const PoseOnlyResult res = ba.TrackFrame(scene.keyframes[9].observations,
                                           PerturbPose(gt, rng, 0.01, 0.1), PoseOnlyOptions());
  ASSERT_EQ(res.status, PoseOnlyStatus::kOk);
  EXPECT_LT((res.T_w_c.translation() - gt.translation()).norm(), 0.02);
  EXPECT_GT(res.num_inliers, 50);
  // Unknown landmarks only: no answer, as a status.
  std::vector<BaObservation> unknown(10);
  for (int i = 0; i < 10; ++i) unknown[i].landmark = LandmarkId(100000 + i);
  EXPECT_EQ(ba.TrackFrame(unknown, gt, PoseOnlyOptions()).status,
            PoseOnlyStatus::kTooFewObservations);
}

TEST(SlidingWindowBaTest, MonoConvergesWithTwoFixedKeyframes) {
  const BaScene scene = MakeBaScene(MonoScene());
  SlidingWindowBa::Options options;
  options.window_size = static_cast<int>(scene.keyframes.size());
  options.max_num_iterations = 50;
  SlidingWindowBa ba(scene.K, options);
  std::mt19937 rng(11);
  SeedLandmarks(scene, 0.1, &rng, &ba);
  std::vector<Pose> init;
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    // Gauge: the first two keyframes are held constant (at the truth here), fixing the scale.
    kf.T_w_c = i < 2 ? scene.T_w_c_gt[i] : PerturbPose(scene.T_w_c_gt[i], rng, 0.01, 0.05);
    init.push_back(kf.T_w_c);
    ba.AddKeyframe(kf);
  }
  const auto s = ba.Optimize();
  ASSERT_TRUE(s.usable) << s.BriefReport();
  double max_err = 0.0, max_err_init = 0.0;
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    max_err = std::max(
        max_err,
        (ba.KeyframePose(KeyframeId(i))->translation() - scene.T_w_c_gt[i].translation()).norm());
    max_err_init =
        std::max(max_err_init, (init[i].translation() - scene.T_w_c_gt[i].translation()).norm());
  }
  EXPECT_GT(max_err_init, 0.08);
  EXPECT_LT(max_err, 0.03) << s.BriefReport();  // no alignment: the gauge is fixed.
}

// One camera holds the last two keyframes to leave the window by default (the scale lives only
// in the views; docs/monocular.md "Held keyframes"); stereo intrinsics hold none (checked at the
// end of HeldKeyframesAreTheLastToLeaveAndMoveWithACorrection).
TEST(SlidingWindowBaTest, MonoHoldsTheLastTwoKeyframesToLeaveByDefault) {
  const BaScene scene = MakeBaScene(MonoScene());
  SlidingWindowBa::Options options;
  options.window_size = 6;
  options.landmark_exit = SlidingWindowBa::LandmarkExit::kDropSharedObservations;
  SlidingWindowBa ba(scene.K, options);
  std::mt19937 rng(5);
  SeedLandmarks(scene, 0.05, &rng, &ba);
  double max_err = 0.0;
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    kf.T_w_c = i < 2 ? scene.T_w_c_gt[i] : PerturbPose(scene.T_w_c_gt[i], rng, 0.01, 0.05);
    ba.AddKeyframe(kf);
    const auto s = ba.Optimize();
    ASSERT_TRUE(s.usable) << s.BriefReport();
    EXPECT_EQ(s.num_held_keyframes, std::min<int>(2, std::max<int>(0, i + 1 - 6))) << i;
    for (KeyframeId id : ba.WindowKeyframes()) {
      max_err = std::max(max_err, (ba.KeyframePose(id)->translation() -
                                   scene.T_w_c_gt[static_cast<size_t>(id.value)].translation())
                                      .norm());
    }
  }
  EXPECT_EQ(ba.HeldKeyframes(), (std::vector<KeyframeId>{KeyframeId(4), KeyframeId(5)}));
  EXPECT_LT(max_err, 0.03);  // No alignment: the first two keyframes hold the gauge.
}

// One camera, a keyframe whose tracks all broke (a jerk): keyframe 6 sees none of the window's
// landmarks, only new ones that keyframe 5 sees too. The two views fix its rotation and
// direction but not its distance: started at twice the true step, with its new landmarks
// scaled alike (every residual zero), the solve leaves it there; the relative pose a bridge
// measured (SlidingWindowBa::AddRelativePosePrior) brings it back.
TEST(SlidingWindowBaTest, RelativePosePriorHoldsTheScaleOfAKeyframeWithOnlyNewLandmarks) {
  const BaScene scene = MakeBaScene(MonoScene());
  constexpr int64_t kNewIds = 100000;
  const Pose& T_w_5 = scene.T_w_c_gt[5];
  const Pose& T_w_6 = scene.T_w_c_gt[6];
  const Pose T_5_6 = T_w_5.inverse() * T_w_6;
  // Keyframe 6 and its new landmarks scaled by 2 about keyframe 5.
  const auto doubled = [&](const Eigen::Vector3d& p_w) {
    return T_w_5 * (2.0 * (T_w_5.inverse() * p_w));
  };
  const auto run = [&](bool with_prior) {
    SlidingWindowBa::Options options;
    options.window_size = 7;
    options.max_num_iterations = 50;
    SlidingWindowBa ba(scene.K, options);
    std::mt19937 rng(3);
    SeedLandmarks(scene, 0.02, &rng, &ba);
    for (int i = 0; i < 6; ++i) ba.AddKeyframe(scene.keyframes[i]);
    BaKeyframe kf6 = scene.keyframes[6];
    kf6.T_w_c = MakePose(T_w_6.rotation(), doubled(T_w_6.translation()));
    for (BaObservation& o : kf6.observations) {
      const int64_t j = o.landmark.value;
      const BaObservation* seen_by_5 = nullptr;
      for (const BaObservation& o5 : scene.keyframes[5].observations) {
        if (o5.landmark.value == j) seen_by_5 = &o5;
      }
      o.landmark = LandmarkId(kNewIds + j);
      if (seen_by_5 == nullptr) continue;
      BaObservation in_5 = *seen_by_5;
      in_5.landmark = o.landmark;
      ba.AddObservation(KeyframeId(5), in_5);
      ba.SetLandmarkPosition(o.landmark, doubled(scene.p_w_gt[static_cast<size_t>(j)]));
    }
    ba.AddKeyframe(kf6);
    if (with_prior) {
      Matrix6d information = Matrix6d::Identity();
      information.topLeftCorner<3, 3>() *= 1e4;  // 0.01 rad
      information.bottomRightCorner<3, 3>() *= 1.0 / std::pow(0.25 * T_5_6.translation().norm(), 2);
      ba.AddRelativePosePrior(KeyframeId(5), KeyframeId(6), T_5_6, information);
    }
    const auto s = ba.Optimize();
    EXPECT_TRUE(s.usable) << s.BriefReport();
    return (ba.KeyframePose(KeyframeId(6))->translation() - T_w_6.translation()).norm() /
           T_5_6.translation().norm();
  };
  const double without = run(false);
  const double with = run(true);
  std::cout << "[ measured ] keyframe 6's position error in steps: " << without
            << " without the prior, " << with << " with it" << std::endl;
  EXPECT_GT(without, 0.5);
  EXPECT_LT(with, 0.1);
}

TEST(SlidingWindowBaTest, GrossOutliersAreRemoved) {
  BaSceneOptions so = SmallScene();
  so.num_keyframes = 12;
  BaScene scene = MakeBaScene(so);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::set<std::pair<int64_t, int64_t>> injected;  // (keyframe, landmark)
  for (BaKeyframe& kf : scene.keyframes) {
    for (BaObservation& obs : kf.observations) {
      if (uni(rng) < 0.1) {
        const double angle = 2.0 * M_PI * uni(rng);
        const double offset = 15.0 + 35.0 * uni(rng);
        obs.uv += offset * Eigen::Vector2d(std::cos(angle), std::sin(angle));
        *obs.u_right += offset * std::cos(angle);
        injected.insert({kf.id.value, obs.landmark.value});
      }
    }
  }
  SlidingWindowBa::Options options;
  options.window_size = so.num_keyframes;
  options.max_num_iterations = 30;
  SlidingWindowBa ba(scene.K, options);
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    kf.T_w_c = i == 0 ? scene.T_w_c_gt[0] : PerturbPose(scene.T_w_c_gt[i], rng, 0.005, 0.03);
    ba.AddKeyframe(kf);
  }
  const auto s = ba.Optimize();
  ASSERT_TRUE(s.usable);
  EXPECT_GE(s.num_outliers_removed, static_cast<int>(0.9 * injected.size())) << s.BriefReport();
  std::vector<Pose> est;
  for (size_t i = 0; i < scene.keyframes.size(); ++i)
    est.push_back(*ba.KeyframePose(KeyframeId(i)));
  EXPECT_LT(AlignedAte(est, scene.T_w_c_gt), 0.01) << s.BriefReport();
}

// A rig whose disparities are all 0.4 px too small (what KITTI's rectification leaves, ~0.3 px):
// estimated with the window (Options::estimate_disparity_offset) or calibrated once for the rig
// from aside solves (Options::calibrate_disparity_offset, the default), the offset is found and
// the scale error it caused is mostly gone.
TEST(SlidingWindowBaTest, EstimatesTheRigsDisparityOffset) {
  BaSceneOptions o = SmallScene();
  o.num_keyframes = 40;
  o.pixel_noise = 0.3;
  BaScene scene = MakeBaScene(o);
  const double offset = 0.4;
  for (BaKeyframe& kf : scene.keyframes) {
    for (BaObservation& obs : kf.observations) {
      if (obs.u_right) *obs.u_right += offset;  // d = u - u_r is `offset` too small.
    }
  }
  SlidingWindowBa::Options options;
  options.estimate_disparity_offset = false;
  options.calibrate_disparity_offset = false;
  SlidingWindowBa ignored(scene.K, options);
  const double ate_ignored = AlignedAte(RunSequential(scene, options, 7, &ignored), scene.T_w_c_gt);
  options.estimate_disparity_offset = true;
  SlidingWindowBa estimated(scene.K, options);
  const double ate_estimated =
      AlignedAte(RunSequential(scene, options, 7, &estimated), scene.T_w_c_gt);
  options.estimate_disparity_offset = false;
  options.calibrate_disparity_offset = true;
  SlidingWindowBa calibrated(scene.K, options);
  const double ate_calibrated =
      AlignedAte(RunSequential(scene, options, 7, &calibrated), scene.T_w_c_gt);
  std::cout << "[ measured ] offset " << estimated.disparity_offset_px() << " px estimated, "
            << calibrated.disparity_offset_px() << " px calibrated (true " << offset << "); ATE "
            << ate_estimated << " m estimated, " << ate_calibrated << " m calibrated, "
            << ate_ignored << " m ignored" << std::endl;
  EXPECT_EQ(ignored.disparity_offset_px(), 0.0);
  EXPECT_NEAR(estimated.disparity_offset_px(), offset, 0.1);
  EXPECT_NEAR(calibrated.disparity_offset_px(), offset, 0.1);
  EXPECT_GE(calibrated.offset_calibration().num_estimates(), 8);
  EXPECT_LT(ate_estimated, 0.5 * ate_ignored);
  EXPECT_LT(ate_calibrated, 0.5 * ate_ignored);
}

// On an exact rig the calibration finds nothing to apply: the window solves never see an offset
// and the trajectory is bit for bit the one without the calibration (it only costs the aside
// solves' time).
TEST(SlidingWindowBaTest, CalibrationLeavesAnExactRigAlone) {
  BaSceneOptions o = SmallScene();
  o.num_keyframes = 40;
  o.pixel_noise = 0.3;
  const BaScene scene = MakeBaScene(o);
  SlidingWindowBa::Options options;
  options.calibrate_disparity_offset = false;
  SlidingWindowBa off(scene.K, options);
  const std::vector<Pose> poses_off = RunSequential(scene, options, 7, &off);
  options.calibrate_disparity_offset = true;
  SlidingWindowBa on(scene.K, options);
  const std::vector<Pose> poses_on = RunSequential(scene, options, 7, &on);
  std::cout << "[ measured ] exact rig: " << on.offset_calibration().num_estimates()
            << " estimates, median " << on.offset_calibration().median_px() << " px" << std::endl;
  EXPECT_GE(on.offset_calibration().num_estimates(), 8);
  EXPECT_EQ(on.disparity_offset_px(), 0.0);
  ASSERT_EQ(poses_on.size(), poses_off.size());
  for (size_t i = 0; i < poses_on.size(); ++i) {
    EXPECT_EQ(poses_on[i].matrix(), poses_off[i].matrix()) << "keyframe " << i;
  }
}

// Options::num_held_keyframes: the last keyframes to leave the window stay beside it as
// constants, at the pose they left with, and their observations of the window's landmarks
// enter every solve; a loop correction moves them with the window.
TEST(SlidingWindowBaTest, HeldKeyframesAreTheLastToLeaveAndMoveWithACorrection) {
  const BaScene scene = MakeBaScene(SmallScene());
  SlidingWindowBa::Options options;
  options.landmark_exit = SlidingWindowBa::LandmarkExit::kDropSharedObservations;
  options.window_size = 6;
  options.num_held_keyframes = 3;
  SlidingWindowBa ba(scene.K, options);
  const double ate = AlignedAte(RunSequential(scene, options, 7, &ba), scene.T_w_c_gt);
  const double ate_batch = AlignedAte(RunBatch(scene, options, 7), scene.T_w_c_gt);
  EXPECT_LT(ate, 2.0 * ate_batch + 0.005) << "batch " << ate_batch;

  const auto& left = ba.marginalized_keyframes();
  ASSERT_EQ(left.size(), scene.keyframes.size() - 6);
  const std::vector<KeyframeId> held = ba.HeldKeyframes();
  ASSERT_EQ(held.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(held[i], left[left.size() - 3 + i].id) << i;
  const SlidingWindowBa::Summary before = ba.Optimize();
  EXPECT_EQ(before.num_held_keyframes, 3) << before.BriefReport();

  // A rigid correction G of everything (window, held keyframes, landmarks) changes no residual:
  // the next solve starts where the last one ended, with every held keyframe still used.
  const Pose G(Eigen::Translation3d(0.4, -0.2, 0.1) *
               Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  std::map<KeyframeId, Pose> corrected;
  for (const auto& m : left) corrected[m.id] = G * m.T_w_c;
  for (KeyframeId id : ba.WindowKeyframes()) corrected[id] = G * *ba.KeyframePose(id);
  for (const auto& [id, p_w] : ba.Landmarks()) ba.SetLandmarkPosition(id, G * p_w);
  ba.ApplyCorrection(corrected);
  const SlidingWindowBa::Summary after = ba.Optimize();
  EXPECT_EQ(after.num_held_keyframes, 3) << after.BriefReport();
  EXPECT_EQ(after.num_outliers_removed, 0) << after.BriefReport();
  // Without the prior (ApplyCorrection drops it) the start cost is the residuals' alone.
  EXPECT_LT(after.initial_cost, 1.5 * before.final_cost) << after.BriefReport();

  // Off by default with stereo intrinsics (the scene's): nothing is held.
  SlidingWindowBa plain(scene.K, SlidingWindowBa::Options());
  RunSequential(scene, SlidingWindowBa::Options(), 7, &plain);
  EXPECT_TRUE(plain.HeldKeyframes().empty());
  EXPECT_EQ(plain.Optimize().num_held_keyframes, 0);
}

TEST(SlidingWindowBaTest, TwoRunsAreBitIdentical) {
  BaSceneOptions so = SmallScene();
  so.num_keyframes = 12;
  const BaScene scene = MakeBaScene(so);
  const auto a = RunSequential(scene, SlidingWindowBa::Options(), 3);
  const auto b = RunSequential(scene, SlidingWindowBa::Options(), 3);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].matrix() == b[i].matrix()) << i;
}

TEST(SlidingWindowBaTest, OptionsValidation) {
  std::string why;
  EXPECT_TRUE(SlidingWindowBa::Options().IsValid(&why));
  SlidingWindowBa::Options o;
  o.window_size = 1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("window_size"), std::string::npos);
  o = SlidingWindowBa::Options();
  o.loss_scale = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  o = SlidingWindowBa::Options();
  o.num_held_keyframes = -2;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("num_held_keyframes"), std::string::npos);
  o = SlidingWindowBa::Options();
  o.max_solver_time_in_seconds = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  StereoIntrinsics K{0.0, 450.0, 320.0, 240.0, 0.5};
  EXPECT_FALSE(K.IsValid(&why));
}

TEST(SlidingWindowBaDeathTest, KeyframeIdsMustIncrease) {
  const StereoIntrinsics K{450.0, 450.0, 320.0, 240.0, 0.5};
  SlidingWindowBa ba(K, SlidingWindowBa::Options());
  BaKeyframe kf;
  kf.id = KeyframeId(3);
  ba.AddKeyframe(kf);
  kf.id = KeyframeId(2);
  EXPECT_DEATH(ba.AddKeyframe(kf), "keyframe ids must increase");
}

TEST(TriangulateStereoTest, DepthFromDisparity) {
  const StereoIntrinsics K{450.0, 400.0, 320.0, 240.0, 0.5};
  BaObservation obs;
  obs.uv = Eigen::Vector2d(320.0 + 45.0, 240.0 - 40.0);
  obs.u_right = obs.uv.x() - 22.5;  // z = 450 * 0.5 / 22.5 = 10.
  const auto p = TriangulateStereo(K, obs, 0.5);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->z(), 10.0, 1e-12);
  EXPECT_NEAR(p->x(), 1.0, 1e-12);
  EXPECT_NEAR(p->y(), -1.0, 1e-12);
  obs.u_right = obs.uv.x() + 1.0;  // negative disparity.
  EXPECT_FALSE(TriangulateStereo(K, obs, 0.5).has_value());
  obs.u_right.reset();
  EXPECT_FALSE(TriangulateStereo(K, obs, 0.5).has_value());
}

}  // namespace
}  // namespace dala
