// MotionEstimator::Estimate3D2D (P3P RANSAC + weighted Gauss-Newton + covariance) on real
// correspondences: the stereo points of one frame matched to the next by the frontend (same
// landmark id), KITTI 06 frames 10 -> 11 and a rendered rover_loop pair.
//   build/benchmarks/motion_benchmark
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/io/dataset.h"
#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "frontend/motion_estimator.h"

namespace dala {
namespace {

// Correspondences between the measurements of two consecutive frames (stereo in the first).
std::vector<MotionCorrespondence> Correspondences(const FrameMeasurement& prev,
                                                  const FrameMeasurement& cur) {
  std::unordered_map<int64_t, const FeatureObservation*> by_id;
  for (const FeatureObservation& o : prev.observations) by_id[o.landmark.value] = &o;
  std::vector<MotionCorrespondence> out;
  for (const FeatureObservation& o : cur.observations) {
    const auto it = by_id.find(o.landmark.value);
    if (it == by_id.end() || !it->second->has_stereo()) continue;
    MotionCorrespondence c;
    c.p_prev = it->second->p_c0;
    c.cov_p_prev = it->second->cov_p_c0;
    c.uv_cur = o.uv;
    c.u_right_cur = o.u_right;
    out.push_back(c);
  }
  return out;
}

void RunMotion(benchmark::State& state, const StereoRig& rig, const Frame& a, const Frame& b) {
  const FrontendOptions options;
  Frontend frontend(rig, options);
  const FrameMeasurement ma = frontend.Process(a);
  const FrameMeasurement mb = frontend.Process(b);
  const std::vector<MotionCorrespondence> corrs = Correspondences(ma, mb);
  const MotionEstimator estimator(rig, options.motion);
  int inliers = 0;
  for (auto _ : state) {
    const auto result = estimator.Estimate3D2D(corrs);
    inliers = result ? result->estimate.inliers : -1;
    benchmark::DoNotOptimize(inliers);
  }
  state.counters["correspondences"] = static_cast<double>(corrs.size());
  state.counters["inliers"] = inliers;
}

void BM_MotionRendered(benchmark::State& state) {
  sim::SimOptions options;
  options.frames = 10;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  RunMotion(state, seq.rig(), seq.Render(4), seq.Render(5));
}
BENCHMARK(BM_MotionRendered)->Unit(benchmark::kMillisecond);

void BM_MotionKitti(benchmark::State& state) {
  const std::string path = std::string(DALA_SHARED_DATA_DIR) + "/kitti06_0000-0050";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared KITTI data absent");
    return;
  }
  auto dataset = OpenDataset(path);
  Frame a, b;
  for (int i = 0; i <= 10 && dataset->Next(&a); ++i) {
  }
  dataset->Next(&b);
  RunMotion(state, dataset->rig(), a, b);
}
BENCHMARK(BM_MotionKitti)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
