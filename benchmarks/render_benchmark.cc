// Rendering speed of the synthetic world: one 752x480 image (frames per second on one core).
//   build/benchmarks/render_benchmark
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "core/sim/synthetic_sequence.h"

namespace {

const dala::sim::SyntheticSequence& Sequence(const std::string& preset) {
  static std::map<std::string, std::unique_ptr<dala::sim::SyntheticSequence>> cache;
  auto& seq = cache[preset];
  if (!seq) {
    dala::sim::SimOptions o;
    o.preset = preset;
    seq = std::make_unique<dala::sim::SyntheticSequence>(o);
  }
  return *seq;
}

// A clean view (RenderView) at frames spread over the sequence.
void BM_RenderView(benchmark::State& state, const std::string& preset) {
  const auto& seq = Sequence(preset);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(seq.RenderView(seq.T_w_c0(i)));
    i = (i + 37) % seq.size();
  }
  state.SetItemsProcessed(state.iterations());  // items/s = frames per second.
}

// A full left image with noise (Render of a mono sequence frame).
void BM_RenderFrameWithNoise(benchmark::State& state) {
  dala::sim::SimOptions o;
  o.stereo = false;
  static const dala::sim::SyntheticSequence seq(o);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(seq.Render(i));
    i = (i + 37) % seq.size();
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_BuildWorld(benchmark::State& state) {
  for (auto _ : state) {
    dala::sim::SimOptions o;
    benchmark::DoNotOptimize(dala::sim::SyntheticSequence(o).size());
  }
}

BENCHMARK_CAPTURE(BM_RenderView, rover_loop, std::string("rover_loop"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderView, flight, std::string("flight"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderView, rotation, std::string("rotation"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderView, fast, std::string("fast"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderView, low_texture, std::string("low_texture"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderView, false_loop, std::string("false_loop"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderFrameWithNoise)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildWorld)->Unit(benchmark::kMillisecond);

}  // namespace
