// Cost of a full evaluation (association, alignment, ATE, RPE, KITTI segments) on a KITTI-sized
// trajectory, and of the time association alone.
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/eval/evaluate.h"

namespace dala {
namespace {

// A 4541-pose loop of ~3.7 km at 10 Hz (the size of KITTI 00), the estimate slightly scaled
// and drifting.
void MakePair(int n, Trajectory* gt, Trajectory* est) {
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    const Eigen::Vector3d p(600 * std::cos(a), 0.5 * std::sin(5 * a), 600 * std::sin(a));
    const Eigen::Matrix3d R = ExpSO3(Eigen::Vector3d(0, -a, 0));
    gt->Add(i * 100000000LL, MakePose(R, p));
    est->Add(i * 100000000LL + 3000000LL,
             MakePose(R * ExpSO3(Eigen::Vector3d(0, 1e-4 * i, 0)), 1.01 * p));
  }
}

void BM_Evaluate(benchmark::State& state) {
  Trajectory gt, est;
  MakePair(static_cast<int>(state.range(0)), &gt, &est);
  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  for (auto _ : state) benchmark::DoNotOptimize(Evaluate(gt, est, options));
}
BENCHMARK(BM_Evaluate)->Arg(4541)->Unit(benchmark::kMillisecond);

void BM_AssociateByTime(benchmark::State& state) {
  Trajectory gt, est;
  MakePair(static_cast<int>(state.range(0)), &gt, &est);
  for (auto _ : state) benchmark::DoNotOptimize(AssociateByTime(gt, est, 10000000));
}
BENCHMARK(BM_AssociateByTime)->Arg(4541)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
