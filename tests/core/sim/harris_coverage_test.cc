// The rendered images must be ones a corner-based frontend can work on: OpenCV's Harris
// detector finds many corners spread over the image in every preset.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "core/sim/synthetic_sequence.h"

namespace dala::sim {
namespace {

struct Coverage {
  int corners = 0;
  int cells = 0;  // Cells of a 4x4 grid holding at least 3 corners.
};

Coverage HarrisCoverage(const cv::Mat& image) {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(image, corners, /*maxCorners=*/1000, /*qualityLevel=*/0.01,
                          /*minDistance=*/7, cv::noArray(), /*blockSize=*/3,
                          /*useHarrisDetector=*/true);
  int count[4][4] = {};
  for (const auto& c : corners) {
    ++count[std::min(3, static_cast<int>(4 * c.y / image.rows))]
           [std::min(3, static_cast<int>(4 * c.x / image.cols))];
  }
  Coverage cov;
  cov.corners = static_cast<int>(corners.size());
  for (auto& row : count) {
    for (int n : row) cov.cells += n >= 3;
  }
  return cov;
}

TEST(HarrisCoverageTest, EveryPresetHasManyWellSpreadCorners) {
  double mean_low_texture = 0, min_mean_rich = 1e9;
  for (const std::string& preset : PresetNames()) {
    SimOptions o;  // Default images: 752x480, noise 1.
    o.preset = preset;
    o.stereo = false;
    const SyntheticSequence seq(o);
    double sum = 0;
    const size_t n = seq.size();
    for (size_t i : {size_t{0}, n / 4 + 3, n / 2 + 1, 3 * n / 4 + 2}) {
      const Coverage cov = HarrisCoverage(seq.Render(i).left);
      EXPECT_GE(cov.corners, 300) << preset << " frame " << i;
      EXPECT_GE(cov.cells, 12) << preset << " frame " << i;
      sum += cov.corners;
    }
    const double mean = sum / 4;
    if (preset == "low_texture") {
      mean_low_texture = mean;
    } else {
      min_mean_rich = std::min(min_mean_rich, mean);
    }
    std::cout << preset << ": mean " << mean << " Harris corners\n";
  }
  EXPECT_LT(mean_low_texture, 0.8 * min_mean_rich);
}

}  // namespace
}  // namespace dala::sim
