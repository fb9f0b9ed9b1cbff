#include "core/eval/chart_drawing.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include "core/error.h"

namespace dala::chart {
namespace {

TEST(ChartDrawing, TicksFallOnRoundNumbers) {
  EXPECT_DOUBLE_EQ(NiceStep(10.0, 5), 2.0);
  EXPECT_DOUBLE_EQ(NiceStep(0.37, 4), 0.1);
  EXPECT_DOUBLE_EQ(NiceStep(700.0, 2), 500.0);
  EXPECT_DOUBLE_EQ(NiceStep(0.0, 5), 1.0);
  EXPECT_DOUBLE_EQ(NiceStep(std::numeric_limits<double>::infinity(), 5), 1.0);
  EXPECT_EQ(TickLabel(0.30000000000000004, 0.1), "0.3");
  EXPECT_EQ(TickLabel(-1e-12, 0.1), "0.0");  // Not "-0.0".
  EXPECT_EQ(TickLabel(1500.0, 500.0), "1500");
  EXPECT_EQ(TickLabel(0.025, 0.005), "0.025");
}

TEST(ChartDrawing, WritesAPngThatReadsBackAndNamesAPathItCannotWrite) {
  const std::string path = ::testing::TempDir() + "/chart_drawing.png";
  cv::Mat img(20, 30, CV_8UC3, cv::Scalar(255, 255, 255));
  PutText(&img, "1", {5, 15}, 0.4, cv::Scalar(0, 0, 0));
  WritePng(img, path);
  const cv::Mat back = cv::imread(path);
  ASSERT_EQ(back.size(), img.size());
  EXPECT_EQ(cv::norm(back, img, cv::NORM_INF), 0.0);
  std::filesystem::remove(path);
  const std::string bad = ::testing::TempDir() + "/no_such_folder/chart.png";
  try {
    WritePng(img, bad);
    FAIL() << "wrote into a missing folder";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dala::chart
