// Sliding-window BA timings on synthetic stereo data (tests/backend/ba/ba_synthetic_scene.h):
// one window optimisation (8 keyframes, ~300 landmarks) and one pose-only optimisation.
//   build/benchmarks/ba_benchmark

#include <benchmark/benchmark.h>

#include "backend/ba/pose_only.h"
#include "backend/ba/sliding_window_ba.h"
#include "tests/backend/ba/ba_synthetic_scene.h"

namespace dala {
namespace {

testing::BaScene WindowScene() {
  testing::BaSceneOptions o;
  o.num_keyframes = 8;
  o.num_points = 300;
  o.pixel_noise = 0.5;
  return testing::MakeBaScene(o);
}

void BM_WindowOptimize(benchmark::State& state) {
  const testing::BaScene scene = WindowScene();
  std::mt19937 rng(1);
  std::vector<BaKeyframe> kfs = scene.keyframes;
  for (size_t i = 1; i < kfs.size(); ++i) {
    kfs[i].T_w_c = testing::PerturbPose(scene.T_w_c_gt[i], rng, 0.005, 0.03);
  }
  int64_t residuals = 0;
  for (auto _ : state) {
    state.PauseTiming();
    SlidingWindowBa ba(scene.K, SlidingWindowBa::Options());
    for (const BaKeyframe& kf : kfs) ba.AddKeyframe(kf);
    state.ResumeTiming();
    const auto s = ba.Optimize();
    residuals = s.num_residual_blocks;
    benchmark::DoNotOptimize(s.final_cost);
  }
  state.counters["residual_blocks"] = static_cast<double>(residuals);
}
BENCHMARK(BM_WindowOptimize)->Unit(benchmark::kMillisecond);

void BM_PoseOnly(benchmark::State& state) {
  const testing::BaScene scene = WindowScene();
  std::mt19937 rng(2);
  const Pose guess = testing::PerturbPose(scene.T_w_c_gt[4], rng, 0.01, 0.1);
  const auto lookup = [&](LandmarkId id) -> std::optional<Eigen::Vector3d> {
    return scene.p_w_gt[id.value];
  };
  for (auto _ : state) {
    const auto res = EstimatePoseOnly(scene.K, scene.keyframes[4].observations, lookup, guess,
                                      PoseOnlyOptions());
    benchmark::DoNotOptimize(res.T_w_c);
  }
  state.counters["observations"] = static_cast<double>(scene.keyframes[4].observations.size());
}
BENCHMARK(BM_PoseOnly)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
