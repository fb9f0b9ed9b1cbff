#include "core/io/tum_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
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

// Three 640x480 frames at 1305031102.175304 + 0.1 i s; ground truth every 0.05 s moving along y.
void WriteTumFolder(const std::string& folder) {
  std::filesystem::create_directories(folder + "/rgb");
  std::string list = "# color images\n# timestamp filename\n";
  for (int i = 0; i < 3; ++i) {
    const std::string t = "1305031102." + std::to_string(175304 + 100000 * i);
    cv::imwrite(folder + "/rgb/" + t + ".png", RandomImage(640, 480, i));
    list += t + " rgb/" + t + ".png\n";
  }
  WriteText(folder + "/rgb.txt", list);
  std::string gt = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  for (int k = 0; k < 4; ++k) {
    gt += "1305031102." + std::to_string(175304 + 50000 * k) + " 0 " + std::to_string(k) +
          " 0 0 0 0 1\n";
  }
  WriteText(folder + "/groundtruth.txt", gt);
}

TEST(TumDataset, ReadsFreiburg1ByNameAndUndistorts) {
  TempDir dir;
  const std::string seq = dir / "rgbd_dataset_freiburg1_xyz";
  WriteTumFolder(seq);
  EXPECT_EQ(DetectDatasetFormat(seq), DatasetFormat::kTum);
  auto dataset = OpenDataset(seq);
  EXPECT_EQ(dataset->format(), DatasetFormat::kTum);
  EXPECT_FALSE(dataset->is_stereo());
  EXPECT_EQ(dataset->size(), 3u);
  const PinholeCamera& cam = dataset->rig().left;
  EXPECT_FALSE(cam.HasDistortion());
  EXPECT_EQ(cam.width, 640);
  EXPECT_EQ(cam.height, 480);
  EXPECT_NEAR(cam.fx, 517.3, 517.3 * 0.15);  // Undistortion (alpha 0) rescales a little.
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.t_ns, 1305031102175304000);
  EXPECT_EQ(frame.left.size(), cv::Size(640, 480));
  ASSERT_TRUE(frame.T_w_c0_gt.has_value());
  EXPECT_NEAR(frame.T_w_c0_gt->translation().y(), 0.0, 1e-9);
  ASSERT_TRUE(dataset->Next(&frame));
  ASSERT_TRUE(frame.T_w_c0_gt.has_value());
  EXPECT_NEAR(frame.T_w_c0_gt->translation().y(), 2.0, 1e-9);  // Sample k = 2.
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_FALSE(frame.T_w_c0_gt.has_value());  // After the last ground-truth sample.
  EXPECT_EQ(dataset->ground_truth()->size(), 2u);
}

TEST(TumDataset, PublishedIntrinsics) {
  const auto fr1 = TumIntrinsicsForSequence("rgbd_dataset_freiburg1_desk");
  ASSERT_TRUE(fr1.has_value());
  EXPECT_DOUBLE_EQ(fr1->fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1->distortion[4], 1.1633);
  const auto fr2 = TumIntrinsicsForSequence("fr2_desk");
  ASSERT_TRUE(fr2.has_value());
  EXPECT_DOUBLE_EQ(fr2->cy, 249.7);
  const auto fr3 = TumIntrinsicsForSequence("rgbd_dataset_freiburg3_long_office_household");
  ASSERT_TRUE(fr3.has_value());
  EXPECT_DOUBLE_EQ(fr3->fy, 539.2);
  EXPECT_FALSE(fr3->HasDistortion());
  EXPECT_FALSE(TumIntrinsicsForSequence("my_kitchen").has_value());
}

TEST(TumDataset, UnknownCameraNeedsCalibration) {
  TempDir dir;
  const std::string seq = dir / "kitchen";
  WriteTumFolder(seq);
  EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("cannot tell the TUM camera"));
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 500\nfy: 500\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n");
  auto dataset = OpenDataset(seq, options);
  EXPECT_DOUBLE_EQ(dataset->rig().left.fx, 500);
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(cv::norm(frame.left, RandomImage(640, 480, 0), cv::NORM_INF), 0);  // No remap.
}

TEST(TumDataset, Errors) {
  TempDir dir;
  const auto fresh = [&](const std::string& name) {
    WriteTumFolder(dir / name);
    return dir / name;
  };
  {
    const std::string seq = fresh("fr1_order");
    WriteText(seq + "/rgb.txt",
              "1305031102.275304 rgb/1305031102.275304.png\n"
              "1305031102.175304 rgb/1305031102.175304.png\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("rgb.txt:2: time"));
  }
  {
    const std::string seq = fresh("fr1_missing");
    WriteText(seq + "/rgb.txt", "1305031102.175304 rgb/nope.png\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("rgb.txt:1: missing image"));
  }
  {
    // rgb.txt lists a third image the folder lacks: refused, unless it is outside the range
    // to run, or allowed (then that frame is a FrameError when read).
    const std::string seq = fresh("fr1_missing_third");
    std::filesystem::remove(seq + "/rgb/1305031102.375304.png");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("rgb.txt:5: missing image"));
    DatasetOptions options;
    options.max_frames = 2;
    EXPECT_EQ(OpenDataset(seq, options)->size(), 2u);
    options.max_frames = 0;
    options.allow_missing_images = true;
    auto dataset = OpenDataset(seq, options);
    Frame frame;
    ASSERT_TRUE(dataset->Next(&frame));
    ASSERT_TRUE(dataset->Next(&frame));
    try {
      dataset->Next(&frame);
      ADD_FAILURE() << "a missing image should be a FrameError";
    } catch (const FrameError& e) {
      EXPECT_EQ(e.frame().value, 2);
      EXPECT_THAT(e.what(), HasSubstr("1305031102.375304.png"));
    }
    EXPECT_FALSE(dataset->Next(&frame));
  }
  {
    const std::string seq = fresh("fr1_fields");
    WriteText(seq + "/rgb.txt", "1305031102.175304\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("expected 't filename'"));
  }
  {
    const std::string seq = fresh("fr1_size");
    cv::imwrite(seq + "/rgb/1305031102.175304.png", RandomImage(320, 240, 0));
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("is 320x240, expected 640x480"));
  }
}

TEST(DatasetFormat, DetectionAndNames) {
  TempDir dir;
  const std::string msg = ErrorOf([&] { DetectDatasetFormat(dir.path()); });
  EXPECT_THAT(msg, HasSubstr("cannot tell the dataset format"));
  EXPECT_THAT(msg, HasSubstr("image_0/"));
  EXPECT_THAT(msg, HasSubstr("mav0/"));
  EXPECT_THAT(msg, HasSubstr("rgb.txt"));
  EXPECT_THAT(msg, HasSubstr("synth.yaml"));
  for (DatasetFormat f : {DatasetFormat::kAuto, DatasetFormat::kKitti, DatasetFormat::kEuroc,
                          DatasetFormat::kTum, DatasetFormat::kSynthetic}) {
    EXPECT_EQ(ParseDatasetFormat(DatasetFormatName(f)), f);
  }
  EXPECT_THAT(ErrorOf([] { ParseDatasetFormat("kiti"); }), HasSubstr("use one of auto, kitti"));
}

}  // namespace
}  // namespace dala
