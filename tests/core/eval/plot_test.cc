#include "core/eval/plot.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "tests/core/eval/eval_test_util.h"
#include "tests/test_util.h"

namespace dala {
namespace {

TEST(PlotEvaluation, WritesAReadablePng) {
  testing::TempDir dir;
  const Trajectory gt = testing::HelixTrajectory(120);
  Trajectory est = gt;
  for (size_t i = 0; i < est.size(); ++i) est.poses[i].T_w_c.translation().x() += 0.01 * (i % 7);
  const EvalResult r = Evaluate(gt, est, EvalOptions());
  ASSERT_TRUE(r.ok);
  const std::string png = dir / "plot.png";
  PlotEvaluation(gt, AlignTrajectory(est, r.alignment), r, png);
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 1200);
  EXPECT_EQ(img.rows, 1200);
  // Both curves are drawn: blue estimate pixels and red error pixels exist.
  int blue = 0, red = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b c = img.at<cv::Vec3b>(y, x);
      if (c[0] > 150 && c[2] < 60) ++blue;
      if (c[2] > 170 && c[0] < 70) ++red;
    }
  }
  EXPECT_GT(blue, 500);
  EXPECT_GT(red, 300);
  // No temporary file is left behind, and an unwritable path is an Error naming it.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.exists();
  EXPECT_EQ(files, 1);
  EXPECT_THROW(PlotEvaluation(gt, est, r, dir / "missing/folder/plot.png"), Error);
}

}  // namespace
}  // namespace dala
