// Frontend speed per stereo frame: detection (both images) + stereo + temporal matching + motion,
// image decoding excluded (frames are rendered or read before the timed loop). Counters: wall
// milliseconds per frame and stage, and cpu_ms = CPU time of all threads per frame.
//   build/benchmarks/frontend_benchmark
//   OPENCV_FOR_THREADS_NUM=1 build/benchmarks/frontend_benchmark   # OpenCV single-threaded
#include <benchmark/benchmark.h>

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <opencv2/core.hpp>

#include "core/io/dataset.h"
#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"

namespace dala {
namespace {

// CPU time of the whole process (all threads), milliseconds: on a machine shared with other jobs
// it is a steadier measure of the work than the wall-clock stage timings.
double ProcessCpuMs() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

void RunFrontend(benchmark::State& state, const StereoRig& rig, const std::vector<Frame>& frames,
                 const FrontendOptions& options) {
  int64_t processed = 0;
  FrontendTimings sum;
  double features = 0;
  const double cpu0 = ProcessCpuMs();
  for (auto _ : state) {
    Frontend frontend(rig, options);
    for (const Frame& f : frames) {
      const FrameMeasurement m = frontend.Process(f);
      sum.detect_ms += m.timings.detect_ms;
      sum.stereo_ms += m.timings.stereo_ms;
      sum.motion_ms += m.timings.motion_ms;
      sum.track_ms += m.timings.track_ms;
      features += m.observations.size();
    }
    processed += static_cast<int64_t>(frames.size());
  }
  // Per-stage wall milliseconds per frame (tracking = temporal matching + motion).
  const double n = static_cast<double>(std::max<int64_t>(processed, 1));
  state.counters["cpu_ms"] = (ProcessCpuMs() - cpu0) / n;  // Frontend construction included.
  state.counters["detect_ms"] = sum.detect_ms / n;
  state.counters["stereo_ms"] = sum.stereo_ms / n;
  state.counters["track_motion_ms"] = sum.motion_ms / n;
  state.counters["reacquire_ms"] = sum.track_ms / n;
  state.counters["features"] = features / n;
}

void BM_FrontendRendered752x480(benchmark::State& state) {
  sim::SimOptions options;
  options.frames = 20;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  std::vector<Frame> frames;
  for (size_t i = 0; i < seq.size(); ++i) frames.push_back(seq.Render(i));
  RunFrontend(state, seq.rig(), frames, FrontendOptions());
}
BENCHMARK(BM_FrontendRendered752x480)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_FrontendKitti1226x370(benchmark::State& state) {
  const std::string path = std::string(DALA_SHARED_DATA_DIR) + "/kitti06_0000-0050";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared KITTI data absent");
    return;
  }
  auto dataset = OpenDataset(path);
  std::vector<Frame> frames;
  Frame f;
  while (dataset->Next(&f) && frames.size() < 20) frames.push_back(f);
  RunFrontend(state, dataset->rig(), frames, FrontendOptions());
}
BENCHMARK(BM_FrontendKitti1226x370)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace
}  // namespace dala
