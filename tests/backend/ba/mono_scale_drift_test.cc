// One camera's scale along a long drive through the sliding window (no images): the window's
// own contribution to the scale drift, free of the frontend's tracks. A camera drives 71 m of a
// curve (radius 60 m, 0.6 m between keyframes) past points at 2-10 m to each side, every point
// observed in every keyframe that sees it (no broken track), and the window runs with the
// options `dala run` uses (SequenceBaOptions). The scale along the path is the length of the
// estimated steps over the true ones, per eighth of the path; its drift is log(last / first).
// docs/monocular.md ("Scale drift: the window and the images") has the measurements.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "backend/ba/sliding_window_ba.h"
#include "backend/sliding_window_estimator.h"
#include "tests/backend/ba/ba_synthetic_scene.h"
#include "tests/backend/ba/window_keyframe_poses.h"

namespace dala {
namespace {

// log(scale of the last eighth / scale of the first eighth) of the window's keyframe path.
double ScaleDrift(const SlidingWindowBa::Options& options, double pixel_noise, unsigned seed) {
  testing::BaSceneOptions o;
  o.stereo = false;
  o.num_keyframes = 120;
  o.num_points = 1500;
  o.step_m = 0.6;
  o.turn_radius_m = 60.0;
  o.pixel_noise = pixel_noise;
  o.seed = seed;
  testing::BaScene scene = testing::MakeBaScene(o);
  SlidingWindowBa ba(scene.K, options);
  // The two previous keyframes are still in the window (it holds more than two).
  const auto pose_of = [&](size_t i) { return *ba.KeyframePose(scene.keyframes[i].id); };
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    for (BaObservation& obs : kf.observations) obs.sigma_px = 1.0;  // Also with exact ones.
    // The gauge pair at the truth; later keyframes from the estimate's constant velocity.
    kf.T_w_c =
        i < 2 ? scene.T_w_c_gt[i] : pose_of(i - 1) * (pose_of(i - 2).inverse() * pose_of(i - 1));
    ba.AddKeyframe(kf);
    EXPECT_TRUE(ba.Optimize().usable);
  }
  const std::vector<Pose> est = testing::AllKeyframePoses(ba);
  const auto scale_of = [&](size_t from, size_t to) {
    double estimated = 0.0, truth = 0.0;
    for (size_t i = from; i < to; ++i) {
      estimated += (est[i + 1].translation() - est[i].translation()).norm();
      truth += (scene.T_w_c_gt[i + 1].translation() - scene.T_w_c_gt[i].translation()).norm();
    }
    return estimated / truth;
  };
  const size_t eighth = (est.size() - 1) / 8;
  return std::log(scale_of(est.size() - 1 - eighth, est.size() - 1) / scale_of(0, eighth));
}

double RmsDrift(const SlidingWindowBa::Options& options, double pixel_noise) {
  double sum = 0.0;
  const std::vector<unsigned> seeds = {1, 2, 3, 4, 5, 6, 7, 8};
  for (unsigned seed : seeds) {
    const double d = ScaleDrift(options, pixel_noise, seed);
    sum += d * d;
  }
  return std::sqrt(sum / seeds.size());
}

// Exact observations: the window keeps the gauge pair's scale to the end of the drive.
TEST(MonoScaleDriftTest, ExactObservationsKeepTheScale) {
  EXPECT_LT(std::abs(ScaleDrift(SequenceBaOptions(), 0.0, 1)), 1e-4);
}

// 1 px of noise: the scale walks. Over eight drives
// its RMS stays within 2.5 % (measured 1.6 %); without the held keyframes
// (SlidingWindowBa::Options::num_held_keyframes = 0) it is 3.9 %.
TEST(MonoScaleDriftTest, NoisyObservationsWalkLittle) {
  EXPECT_LT(RmsDrift(SequenceBaOptions(), 1.0), 0.025);
}

}  // namespace
}  // namespace dala
