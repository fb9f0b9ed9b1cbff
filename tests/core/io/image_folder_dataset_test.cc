// Plain image folders with a calibration file (core/io/image_folder_dataset.h).
#include "core/io/image_folder_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "core/io/dataset.h"
#include "tests/core/io/dataset_fixtures.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ErrorOf;
using ::testing::HasSubstr;
using testing::RandomImage;
using testing::TempDir;
using testing::WriteText;

constexpr const char* kCalibration =
    "%YAML:1.0\nfx: 80\nfy: 80\ncx: 31.5\ncy: 23.5\nwidth: 64\nheight: 48\n";

void WriteImages(const std::string& folder, const std::vector<std::string>& names, int seed0,
                 cv::Size size = cv::Size(64, 48)) {
  std::filesystem::create_directories(folder);
  for (size_t i = 0; i < names.size(); ++i) {
    cv::imwrite(folder + "/" + names[i], RandomImage(size.width, size.height, seed0 + int(i)));
  }
}

TEST(ImageFolderDataset, DetectedSortedByNumberTimedByFps) {
  TempDir dir;
  // Unpadded numbers: 2 before 10; a jpg among pngs.
  WriteImages(dir / "imgs", {"1.png", "2.png", "10.jpg"}, 0);
  WriteText(dir / "cam.yaml", kCalibration);
  EXPECT_EQ(DetectDatasetFormat(dir / "imgs"), DatasetFormat::kImages);
  const auto files = ListImageFiles(dir / "imgs");
  ASSERT_EQ(files.size(), 3u);
  EXPECT_THAT(files[1], HasSubstr("2.png"));
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  // Frame numbers are not times: --fps or a times file is asked for.
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "imgs", options); }), HasSubstr("--fps"));
  options.fps = 20;
  auto dataset = OpenDataset(dir / "imgs", options);
  EXPECT_EQ(dataset->format(), DatasetFormat::kImages);
  EXPECT_FALSE(dataset->is_stereo());
  EXPECT_EQ(dataset->size(), 3u);
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.t_ns, 50000000);
  EXPECT_EQ(cv::norm(frame.left, RandomImage(64, 48, 1), cv::NORM_INF), 0);
}

TEST(ImageFolderDataset, TimesFromNamesOrTimesFile) {
  TempDir dir;
  WriteText(dir / "cam.yaml", kCalibration);
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  WriteImages(dir / "ns", {"1403636579763555584.png", "1403636579813555456.png"}, 0);
  auto ns = OpenDataset(dir / "ns", options);
  Frame frame;
  ASSERT_TRUE(ns->Next(&frame));
  EXPECT_EQ(frame.t_ns, 1403636579763555584);
  WriteImages(dir / "s", {"12.5.png", "12.75.png"}, 0);
  auto s = OpenDataset(dir / "s", options);
  ASSERT_TRUE(s->Next(&frame));
  ASSERT_TRUE(s->Next(&frame));
  EXPECT_EQ(frame.t_ns, 12750000000);
  WriteImages(dir / "named", {"frame_a.png", "frame_b.png"}, 0);
  WriteText(dir / "times.txt", "0.0\n0.25\n");
  options.times_file = dir / "times.txt";
  auto named = OpenDataset(dir / "named", options);
  ASSERT_TRUE(named->Next(&frame));
  ASSERT_TRUE(named->Next(&frame));
  EXPECT_EQ(frame.t_ns, 250000000);
  WriteText(dir / "times.txt", "0.0\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "named", options); }),
              HasSubstr("1 times for the 2 images"));
}

TEST(ImageFolderDataset, StereoFolderRectifiedAtOpenFromKalibr) {
  TempDir dir;
  const std::vector<std::string> names = {"a.png", "b.png"};
  WriteImages(dir / "left", names, 0, cv::Size(752, 480));
  WriteImages(dir / "right", {"x.png", "y.png"}, 100, cv::Size(752, 480));
  DatasetOptions options;
  options.calibration_yaml =
      std::string(DALA_SOURCE_DIR) + "/tests/core/io/data/kalibr_camchain_radtan.yaml";
  options.right_folder = dir / "right";
  options.fps = 10;
  auto dataset = OpenDataset(dir / "left", options);
  EXPECT_TRUE(dataset->is_stereo());
  EXPECT_NEAR(dataset->rig().baseline, 0.110, 0.001);
  EXPECT_FALSE(dataset->rig().left.HasDistortion());
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.right.size(), cv::Size(752, 480));
  // One right image short, under other names: refused.
  std::filesystem::remove(dir / "right/y.png");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "left", options); }),
              HasSubstr("holds 1 images for the 2"));
}

TEST(ImageFolderDataset, BadInputNamesTheFileAndTheFix) {
  TempDir dir;
  WriteImages(dir / "imgs", {"0.1.png", "0.2.png"}, 0);
  DatasetOptions options;
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "imgs", options); }),
              HasSubstr("needs its camera calibration: give --calibration"));
  // A calibration of another image size.
  WriteText(dir / "cam.yaml", "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 640\nheight: 480\n");
  options.calibration_yaml = dir / "cam.yaml";
  const std::string size = ErrorOf([&] { OpenDataset(dir / "imgs", options); });
  EXPECT_THAT(size, HasSubstr("is 64x48, expected 640x480"));
  EXPECT_THAT(size, HasSubstr(dir / "cam.yaml"));
  // Options of other formats are refused, not ignored.
  options.stereo_layout = "side_by_side";
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "imgs", options); }), HasSubstr("applies to videos"));
}

}  // namespace
}  // namespace dala
