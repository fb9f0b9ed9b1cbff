// EKF costs: one stereo EKF frame (prediction, update, map management) with 100 and 300
// landmarks in the state, and one monocular EKF frame.
//   ./build/benchmarks/ekf_benchmark

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "backend/ekf/mono_ekf.h"
#include "backend/ekf/stereo_ekf.h"

namespace dala {
namespace {

StereoRig Rig() {
  StereoRig rig;
  rig.left.width = 640;
  rig.left.height = 480;
  rig.left.fx = rig.left.fy = 400.0;
  rig.left.cx = 319.5;
  rig.left.cy = 239.5;
  rig.baseline = 0.5;
  return rig;
}

// A camera moving forward slowly in front of `n` points that all stay in view; frame k.
FrameMeasurement MakeFrame(const StereoRig& rig, const std::vector<Eigen::Vector3d>& points, int k,
                           bool stereo, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.5);
  FrameMeasurement m;
  m.frame = FrameId(k);
  m.t_ns = k * 100000000LL;
  m.stereo = stereo;
  const Pose T_w_c = MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.05 * k));
  if (k > 0) {
    MotionEstimate motion;
    motion.T_prev_cur = MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.05));
    Vector6d var;
    var << 1e-5, 1e-5, 1e-5, 1e-4, 1e-4, 1e-4;
    motion.cov = var.asDiagonal();
    m.motion = motion;
    m.odometry = motion;
    m.status = TrackingStatus::kTracking;
  }
  for (size_t j = 0; j < points.size(); ++j) {
    const Eigen::Vector3d p_c = T_w_c.inverse() * points[j];
    Eigen::Vector3d uvd;
    if (!rig.ProjectStereo(p_c, &uvd)) continue;
    FeatureObservation obs;
    obs.landmark = LandmarkId(static_cast<int64_t>(j));
    obs.uv = uvd.head<2>() + Eigen::Vector2d(noise(*rng), noise(*rng));
    obs.sigma_px = 0.5;
    obs.track_length = k + 1;
    if (stereo) {
      obs.u_right = uvd.x() - uvd.z() + noise(*rng);
      const Eigen::Vector3d z(obs.uv.x(), obs.uv.y(), obs.uv.x() - *obs.u_right);
      rig.Triangulate(z, &obs.p_c0);
      obs.cov_p_c0 = rig.TriangulationCovariance(z, 0.5, 0.7);
    }
    m.observations.push_back(obs);
  }
  return m;
}

std::vector<Eigen::Vector3d> Points(int n) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < n; ++j) {
    const double z = 8 + 4 * u(rng);
    points.emplace_back(0.7 * z * u(rng), 0.5 * z * u(rng), z);
  }
  return points;
}

void BM_StereoEkfFrame(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const StereoRig rig = Rig();
  const std::vector<Eigen::Vector3d> points = Points(n);
  StereoEkfOptions options;
  options.max_landmarks = n;
  options.target_per_zone = n;  // Fill the state quickly.
  options.new_per_zone_per_frame = n;
  options.max_relative_depth_sigma = 1.0;
  StereoEkfEstimator ekf(rig, options);
  std::mt19937 rng(2);
  int k = 0;
  for (; ekf.state().num_landmarks() < n && k < 50; ++k)
    ekf.Add(MakeFrame(rig, points, k, true, &rng));
  const FrameMeasurement next = MakeFrame(rig, points, k, true, &rng);
  for (auto _ : state) {
    state.PauseTiming();
    StereoEkfEstimator copy = ekf;
    state.ResumeTiming();
    benchmark::DoNotOptimize(copy.Add(next));
  }
  state.counters["landmarks"] = ekf.state().num_landmarks();
  state.counters["observations"] = static_cast<double>(next.observations.size());
}
BENCHMARK(BM_StereoEkfFrame)->Arg(100)->Arg(300)->Unit(benchmark::kMillisecond);

void BM_MonoEkfFrame(benchmark::State& state) {
  const StereoRig rig = Rig();
  const std::vector<Eigen::Vector3d> points = Points(300);
  MonoEkfEstimator ekf(rig.left);
  std::mt19937 rng(2);
  int k = 0;
  for (; k < 40; ++k) ekf.Add(MakeFrame(rig, points, k, false, &rng));
  const FrameMeasurement next = MakeFrame(rig, points, k, false, &rng);
  for (auto _ : state) {
    state.PauseTiming();
    MonoEkfEstimator copy = ekf;
    state.ResumeTiming();
    benchmark::DoNotOptimize(copy.Add(next));
  }
  state.counters["landmarks"] = ekf.state().num_landmarks();
  state.counters["candidates"] = ekf.last_stats().candidates;
}
BENCHMARK(BM_MonoEkfFrame)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
