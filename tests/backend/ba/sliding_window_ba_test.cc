#include "backend/ba/sliding_window_ba.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/backend/ba/ba_synthetic_scene.h"

namespace dala {
namespace {

using testing::AlignedAte;
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
    T_prev_cur[i] = PerturbPose(scene.T_w_c_gt[i - 1].inverse() * scene.T_w_c_gt[i], rng, 0.005,
                                0.03);
  }
  return T_prev_cur;
}

std::vector<Pose> AllKeyframePoses(const SlidingWindowBa& ba) {
  std::vector<Pose> out;
  for (const auto& m : ba.marginalized_keyframes()) out.push_back(m.T_w_c);
  for (KeyframeId id : ba.WindowKeyframes()) out.push_back(*ba.KeyframePose(id));
  return out;
}

// Feeds the scene keyframe by keyframe, optimising after each one (the online use).
std::vector<Pose> RunSequential(const BaScene& scene, const SlidingWindowBa::Options& options,
                                unsigned seed, std::vector<SlidingWindowBa::Summary>* summaries =
                                                   nullptr) {
  SlidingWindowBa ba(scene.K, options);
  const auto T_prev_cur = NoisyRelativeMotions(scene, seed);
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    kf.T_w_c = i == 0 ? scene.T_w_c_gt[0]
                      : *ba.KeyframePose(scene.keyframes[i - 1].id) * T_prev_cur[i];
    ba.AddKeyframe(kf);
    const auto s = ba.Optimize();
    EXPECT_TRUE(s.usable) << s.BriefReport();
    if (summaries) summaries->push_back(s);
  }
  return AllKeyframePoses(ba);
}

// All keyframes in one window, initialised by chaining the noisy relative motions.
std::vector<Pose> RunBatch(const BaScene& scene, SlidingWindowBa::Options options, unsigned seed,
                           SlidingWindowBa::Summary* summary = nullptr) {
  options.window_size = static_cast<int>(scene.keyframes.size());
  options.max_num_iterations = 50;
  options.max_solver_time_in_seconds = 20.0;
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

TEST(SlidingWindowBaTest, Explore) {
  const BaScene scene = MakeBaScene(BaSceneOptions());
  SlidingWindowBa::Options options;
  SlidingWindowBa::Summary bs;
  const auto batch = RunBatch(scene, options, 7, &bs);
  std::vector<Pose> init;
  {
    const auto T_prev_cur = NoisyRelativeMotions(scene, 7);
    Pose T = scene.T_w_c_gt[0];
    for (size_t i = 0; i < scene.keyframes.size(); ++i) {
      if (i > 0) T = T * T_prev_cur[i];
      init.push_back(T);
    }
  }
  std::vector<SlidingWindowBa::Summary> ws;
  const auto window = RunSequential(scene, options, 7, &ws);
  options.use_marginalization = false;
  const auto noprior = RunSequential(scene, options, 7);
  printf("init ATE %.4f batch %.4f window %.4f noprior %.4f\n", AlignedAte(init, scene.T_w_c_gt),
         AlignedAte(batch, scene.T_w_c_gt), AlignedAte(window, scene.T_w_c_gt),
         AlignedAte(noprior, scene.T_w_c_gt));
  printf("%s\n", bs.BriefReport().c_str());
  printf("%s\n", ws.back().BriefReport().c_str());
  size_t nobs = 0;
  for (auto& kf : scene.keyframes) nobs += kf.observations.size();
  printf("obs/kf %.1f\n", double(nobs) / scene.keyframes.size());
}

}  // namespace
}  // namespace dala
