// Stereo matching speed: MatchStereo (epipolar-band matching, sub-pixel disparity, triangulation
// and covariance) on one rectified pair whose two images are already detected (detection is
// harris_benchmark's job). Counter `matched` = left points with a stereo match.
//   build/benchmarks/stereo_benchmark
#include <benchmark/benchmark.h>

#include <filesystem>

#include "core/io/dataset.h"
#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "frontend/stereo.h"

namespace dala {
namespace {

void RunStereo(benchmark::State& state, const StereoRig& rig, const Frame& frame) {
  const HarrisOptions harris = SequenceHarrisOptions();
  const DetectedImage left = DetectHarris(frame.left, harris);
  const DetectedImage right = DetectHarris(frame.right, harris);
  const StereoOptions options;
  size_t matched = 0;
  for (auto _ : state) {
    const auto stereo = MatchStereo(rig, left, right, frame.left, frame.right, options);
    matched = 0;
    for (const auto& s : stereo) matched += s.has_value();
    benchmark::DoNotOptimize(stereo.data());
  }
  state.counters["left_points"] = static_cast<double>(left.points.size());
  state.counters["matched"] = static_cast<double>(matched);
}

void BM_StereoRendered752x480(benchmark::State& state) {
  sim::SimOptions options;
  options.frames = 2;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  RunStereo(state, seq.rig(), seq.Render(1));
}
BENCHMARK(BM_StereoRendered752x480)->Unit(benchmark::kMillisecond);

void BM_StereoKitti1226x370(benchmark::State& state) {
  const std::string path = std::string(DALA_SHARED_DATA_DIR) + "/kitti06_0000-0050";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared KITTI data absent");
    return;
  }
  auto dataset = OpenDataset(path);
  Frame frame;
  dataset->Next(&frame);
  RunStereo(state, dataset->rig(), frame);
}
BENCHMARK(BM_StereoKitti1226x370)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
