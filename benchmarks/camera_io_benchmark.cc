// Camera model and dataset reading costs.
//   build/benchmarks/camera_io_benchmark
// Dataset benchmarks read the shared real samples and are skipped when they are absent.

#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

#include "core/camera.h"
#include "core/io/dataset.h"

namespace dala {
namespace {

PinholeCamera EurocCam0() {
  PinholeCamera cam;
  cam.width = 752;
  cam.height = 480;
  cam.fx = 458.654;
  cam.fy = 457.296;
  cam.cx = 367.215;
  cam.cy = 248.375;
  cam.distortion << -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0;
  return cam;
}

void BM_ProjectWithJacobian(benchmark::State& state) {
  PinholeCamera cam = EurocCam0();
  if (state.range(0) == 0) cam.distortion.setZero();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> points(1024);
  for (auto& p : points) p = Eigen::Vector3d(u(rng), 0.6 * u(rng), 2.0 + u(rng));
  size_t i = 0;
  Eigen::Vector2d uv;
  Eigen::Matrix<double, 2, 3> J;
  for (auto _ : state) {
    benchmark::DoNotOptimize(cam.Project(points[i++ & 1023], &uv, &J));
    benchmark::DoNotOptimize(uv);
    benchmark::DoNotOptimize(J);
  }
}
BENCHMARK(BM_ProjectWithJacobian)->Arg(0)->Arg(1)->ArgName("distorted");

void BM_Unproject(benchmark::State& state) {
  PinholeCamera cam = EurocCam0();
  if (state.range(0) == 0) cam.distortion.setZero();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector2d> pixels(1024);
  for (auto& p : pixels) p = Eigen::Vector2d(u(rng) * 751, u(rng) * 479);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(cam.Unproject(pixels[i++ & 1023]));
}
BENCHMARK(BM_Unproject)->Arg(0)->Arg(1)->ArgName("distorted");

// Reading (and for EuRoC rectifying) one stereo frame.
void BM_DatasetNext(benchmark::State& state, const char* sample) {
  const std::string folder = std::string(DALA_SHARED_DATA_DIR) + "/" + sample;
  if (!std::filesystem::exists(folder)) {
    state.SkipWithError("shared data absent");
    return;
  }
  auto dataset = OpenDataset(folder);
  Frame frame;
  for (auto _ : state) {
    if (!dataset->Next(&frame)) {
      dataset->Rewind();
      dataset->Next(&frame);
    }
    benchmark::DoNotOptimize(frame.left.data);
  }
}
BENCHMARK_CAPTURE(BM_DatasetNext, kitti, "kitti06_0000-0050")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DatasetNext, euroc, "euroc_v101_micro")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dala
