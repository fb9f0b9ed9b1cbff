// MatchStereo per stereo pair (matching + sub-pixel refinement + triangulation), detection done
// once before the timed loop. One core's worth of work (no threads inside MatchStereo).
//   build/benchmarks/stereo_benchmark
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "core/io/dataset.h"
#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "frontend/stereo.h"

namespace dala {
namespace {

void RunStereo(benchmark::State& state, const StereoRig& rig, const Frame& frame,
               const StereoOptions& options) {
  const HarrisOptions harris = SequenceHarrisOptions();
  const DetectedImage left = DetectHarris(frame.left, harris);
  const DetectedImage right = DetectHarris(frame.right, harris);
  int with_depth = 0;
  for (auto _ : state) {
    const auto stereo = MatchStereo(rig, left, right, frame.left, frame.right, options);
    with_depth = 0;
    for (const auto& p : stereo) with_depth += p.has_value();
    benchmark::DoNotOptimize(stereo.data());
  }
  state.counters["left_points"] = static_cast<double>(left.points.size());
  state.counters["with_depth"] = with_depth;
}

// Arg: refine_disparity (0 or 1).
void BM_StereoRendered752x480(benchmark::State& state) {
  sim::SimOptions options;
  options.frames = 10;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  StereoOptions stereo;
  stereo.refine_disparity = state.range(0) != 0;
  RunStereo(state, seq.rig(), seq.Render(5), stereo);
}
BENCHMARK(BM_StereoRendered752x480)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_StereoKitti1226x370(benchmark::State& state) {
  const std::string path = std::string(DALA_SHARED_DATA_DIR) + "/kitti06_0000-0050";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared KITTI data absent");
    return;
  }
  auto dataset = OpenDataset(path);
  Frame frame;
  for (int i = 0; i <= 10 && dataset->Next(&frame); ++i) {
  }
  StereoOptions stereo;
  stereo.refine_disparity = state.range(0) != 0;
  RunStereo(state, dataset->rig(), frame, stereo);
}
BENCHMARK(BM_StereoKitti1226x370)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
