// Visual motion estimation speed: MotionEstimator::Estimate3D2D (seeded P3P RANSAC + weighted
// Gauss-Newton on (u, v, d)) on N stereo correspondences with 30 % outliers. The 3D points are
// the real stereo points of a rendered frame (their real covariances); the current observations
// are their projections through a known 0.5 m / 2 deg motion plus 0.5 px noise, and outliers are
// moved 10-60 px. Counter `inliers` = inliers found (70 % of N expected).
//   build/benchmarks/motion_benchmark
#include <benchmark/benchmark.h>

#include <random>

#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "frontend/motion_estimator.h"
#include "frontend/stereo.h"

namespace dala {
namespace {

std::vector<MotionCorrespondence> MakeCorrespondences(const StereoRig& rig, const Frame& frame,
                                                      size_t count) {
  const DetectedImage left = DetectHarris(frame.left, SequenceHarrisOptions());
  const DetectedImage right = DetectHarris(frame.right, SequenceHarrisOptions());
  const auto stereo = MatchStereo(rig, left, right, frame.left, frame.right, StereoOptions());
  const Pose T_prev_cur = MakePose(ExpSO3(Eigen::Vector3d(0.01, 0.03, 0.005)),
                                   Eigen::Vector3d(0.05, -0.02, 0.5));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::uniform_real_distribution<double> offset(10.0, 60.0);
  std::bernoulli_distribution outlier(0.3), sign(0.5);
  std::vector<MotionCorrespondence> out;
  for (const auto& s : stereo) {
    if (!s || out.size() >= count) continue;
    Eigen::Vector3d uvd;
    if (!rig.ProjectStereo(T_prev_cur.inverse() * s->p_c0, &uvd)) continue;
    MotionCorrespondence m;
    m.p_prev = s->p_c0;
    m.cov_p_prev = s->cov_p_c0;
    m.uv_cur = uvd.head<2>() + Eigen::Vector2d(noise(rng), noise(rng));
    m.u_right_cur = m.uv_cur.x() - uvd.z() + noise(rng);
    if (outlier(rng)) {
      m.uv_cur.x() += (sign(rng) ? 1 : -1) * offset(rng);
      m.uv_cur.y() += (sign(rng) ? 1 : -1) * offset(rng);
    }
    out.push_back(m);
  }
  return out;
}

void BM_MotionStereo(benchmark::State& state) {
  sim::SimOptions options;
  options.frames = 2;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  const std::vector<MotionCorrespondence> matches =
      MakeCorrespondences(seq.rig(), seq.Render(1), static_cast<size_t>(state.range(0)));
  if (matches.size() < static_cast<size_t>(state.range(0))) {
    state.SkipWithError("fewer stereo points than requested correspondences");
    return;
  }
  const MotionEstimator estimator(seq.rig(), MotionEstimatorOptions());
  int inliers = 0;
  for (auto _ : state) {
    const auto result = estimator.Estimate3D2D(matches);
    inliers = result ? result->estimate.inliers : 0;
    benchmark::DoNotOptimize(result);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_MotionStereo)->Arg(100)->Arg(300)->Arg(500)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
