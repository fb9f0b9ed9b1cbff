// Detection time of the precise Harris detector (with descriptors) on a KITTI image (1226x370,
// skipped when the shared data is absent) and a 752x480 procedural image, against OpenCV's
// cornerHarris on the same image for reference, plus the matcher on a rotated pair. OpenCV runs
// single-threaded here so that the numbers are per core.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "frontend/frontend.h"
#include "frontend/harris.h"
#include "frontend/matcher.h"
#include "frontend/worker_thread.h"
#include "tests/frontend/test_images.h"

namespace {

cv::Mat KittiImage() {
  const std::string path =
      std::string(DALA_SHARED_DATA_DIR) + "/kitti06_0000-0050/image_0/000000.png";
  if (!std::filesystem::exists(path)) return cv::Mat();
  return cv::imread(path, cv::IMREAD_GRAYSCALE);
}

// One core: OpenCV's own threads would hide the cost from the CPU-time column.
const bool kSingleThread = [] {
  cv::setNumThreads(1);
  return true;
}();

cv::Mat ImageFor(int which) {
  return which == 0 ? KittiImage() : dala::testing::MakeTexturedImage(752, 480, 11);
}

void BM_DetectHarris(benchmark::State& state) {
  const cv::Mat img = ImageFor(static_cast<int>(state.range(0)));
  if (img.empty()) {
    state.SkipWithError("shared data kitti06_0000-0050 absent");
    return;
  }
  dala::HarrisOptions options;
  options.num_levels = static_cast<int>(state.range(1));
  size_t n = 0;
  for (auto _ : state) {
    const dala::DetectedImage d = dala::DetectHarris(img, options);
    n = d.points.size();
    benchmark::DoNotOptimize(d.points.data());
  }
  state.counters["points"] = static_cast<double>(n);
}
// Args: {image (0 KITTI 1226x370, 1 procedural 752x480), pyramid levels}.
BENCHMARK(BM_DetectHarris)
    ->Args({0, 1})
    ->Args({0, 4})
    ->Args({1, 1})
    ->Args({1, 4})
    ->Unit(benchmark::kMillisecond);

// The frontend's per-image detection (SequenceHarrisOptions: 2 levels, <= 1000 points); second
// argument 1: with a helper thread (what one camera does with its idle core; same result).
void BM_DetectHarrisSequence(benchmark::State& state) {
  const cv::Mat img = ImageFor(static_cast<int>(state.range(0)));
  if (img.empty()) {
    state.SkipWithError("shared data kitti06_0000-0050 absent");
    return;
  }
  const dala::HarrisOptions options = dala::SequenceHarrisOptions();
  dala::WorkerThread helper;
  dala::WorkerThread* with = state.range(1) ? &helper : nullptr;
  size_t n = 0;
  for (auto _ : state) {
    const dala::DetectedImage d = dala::DetectHarris(img, options, with);
    n = d.points.size();
    benchmark::DoNotOptimize(d.points.data());
  }
  state.counters["points"] = static_cast<double>(n);
}
BENCHMARK(BM_DetectHarrisSequence)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond);

void BM_OpenCvCornerHarris(benchmark::State& state) {
  const cv::Mat img = ImageFor(static_cast<int>(state.range(0)));
  if (img.empty()) {
    state.SkipWithError("shared data kitti06_0000-0050 absent");
    return;
  }
  cv::Mat r;
  for (auto _ : state) {
    cv::cornerHarris(img, r, 2, 3, 0.04);
    benchmark::DoNotOptimize(r.data);
  }
}
BENCHMARK(BM_OpenCvCornerHarris)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_MatchRotated(benchmark::State& state) {
  const cv::Mat a = dala::testing::MakeTexturedImage(752, 480, 11);
  const cv::Mat b = dala::testing::Warp(
      a, dala::testing::SimilarityAboutCentre(a.size(), state.range(0) * M_PI / 180.0, 1.0));
  dala::HarrisOptions ho;
  const dala::DetectedImage da = dala::DetectHarris(a, ho), db = dala::DetectHarris(b, ho);
  dala::MatcherOptions mo;
  size_t n = 0;
  for (auto _ : state) {
    n = dala::MatchPoints(da, db, mo).size();
  }
  state.counters["matches"] = static_cast<double>(n);
  state.counters["points"] = static_cast<double>(da.points.size());
}
BENCHMARK(BM_MatchRotated)->Arg(0)->Arg(45)->Unit(benchmark::kMillisecond);

}  // namespace
