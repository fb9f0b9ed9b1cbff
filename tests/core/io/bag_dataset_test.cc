// ROS 1 bags (core/io/bag_dataset.h) that the test writes with rosbag: sensor_msgs/Image (mono8,
// bgr8, rgb8) and CompressedImage, CameraInfo from the bag, stereo pairing, and the errors.
// Skipped with a message on a build without librosbag-dev / libsensor-msgs-dev.
#include "core/io/bag_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/io/dataset.h"
#include "tests/core/io/dataset_fixtures.h"
#include "tests/test_util.h"

#ifdef DALA_HAVE_ROSBAG
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#endif

namespace dala {
namespace {

using testing::ErrorOf;
using ::testing::HasSubstr;
using testing::RandomImage;
using testing::TempDir;
using testing::WriteText;

#ifndef DALA_HAVE_ROSBAG

TEST(BagDataset, SaysHowToGetBagSupport) {
  TempDir dir;
  WriteText(dir / "x.bag", "not read");
  EXPECT_FALSE(HaveBagSupport());
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "x.bag"); }), HasSubstr("install librosbag-dev"));
  GTEST_SKIP() << "this build reads no ROS bags (librosbag-dev / libsensor-msgs-dev absent at "
                  "configure time): the bag reader's tests are skipped";
}

#else

sensor_msgs::Image ImageMsg(const cv::Mat& gray, const std::string& encoding, int64_t t_ns) {
  sensor_msgs::Image m;
  m.header.stamp.fromNSec(static_cast<uint64_t>(t_ns));
  m.width = static_cast<uint32_t>(gray.cols);
  m.height = static_cast<uint32_t>(gray.rows);
  m.encoding = encoding;
  cv::Mat data = gray;
  if (encoding == "bgr8") cv::cvtColor(gray, data, cv::COLOR_GRAY2BGR);
  if (encoding == "rgb8") cv::cvtColor(gray, data, cv::COLOR_GRAY2RGB);
  m.step = static_cast<uint32_t>(data.cols * data.elemSize());
  m.data.assign(data.data, data.data + data.total() * data.elemSize());
  return m;
}

sensor_msgs::CameraInfo InfoMsg(int w, int h, double tx) {
  sensor_msgs::CameraInfo info;
  info.width = w;
  info.height = h;
  info.distortion_model = "plumb_bob";
  info.D = {-0.1, 0.01, 0, 0, 0};
  info.K = {80, 0, 31.5, 0, 80, 23.5, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {80, 0, 31.5, tx, 0, 80, 23.5, 0, 0, 0, 1, 0};
  return info;
}

// Frame i of the left camera: RandomImage(64, 48, i), right 100 + i; stamps 1 s + i * 50 ms.
void WriteBag(const std::string& path, const std::string& encoding, bool compressed,
              bool stereo, bool info) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int i = 0; i < 4; ++i) {
    const int64_t t = 1000000000 + i * 50000000;
    ros::Time stamp;
    stamp.fromNSec(static_cast<uint64_t>(t));
    if (compressed) {
      sensor_msgs::CompressedImage m;
      m.header.stamp = stamp;
      m.format = "png";
      cv::imencode(".png", RandomImage(64, 48, i), m.data);
      bag.write("/cam0/image_raw/compressed", stamp, m);
    } else {
      bag.write("/cam0/image_raw", stamp, ImageMsg(RandomImage(64, 48, i), encoding, t));
    }
    if (stereo) bag.write("/cam1/image_raw", stamp, ImageMsg(RandomImage(64, 48, 100 + i), encoding, t));
    if (info) {
      bag.write("/cam0/camera_info", stamp, InfoMsg(64, 48, 0));
      if (stereo) bag.write("/cam1/camera_info", stamp, InfoMsg(64, 48, -80 * 0.12));
    }
    bag.write("/imu", stamp, sensor_msgs::CameraInfo());  // Another topic, ignored.
  }
}

TEST(BagDataset, ImagesOfEveryEncodingWithTheBagsCameraInfo) {
  TempDir dir;
  for (const std::string encoding : {"mono8", "bgr8", "rgb8"}) {
    const std::string path = dir / (encoding + ".bag");
    WriteBag(path, encoding, false, false, true);
    EXPECT_EQ(DetectDatasetFormat(path), DatasetFormat::kBag);
    DatasetOptions options;
    options.topic = "/cam0/image_raw";
    options.first_frame = 1;
    auto bag = OpenDataset(path, options);
    EXPECT_EQ(bag->format(), DatasetFormat::kBag);
    EXPECT_EQ(bag->size(), 3u);
    EXPECT_FALSE(bag->is_stereo());
    EXPECT_FALSE(bag->rig().left.HasDistortion());  // Undistorted from the CameraInfo.
    Frame frame;
    ASSERT_TRUE(bag->Next(&frame));
    EXPECT_EQ(frame.id.value, 1);
    EXPECT_EQ(frame.t_ns, 1050000000);
    EXPECT_EQ(frame.left.size(), cv::Size(64, 48));
    // A calibration file instead: no distortion, so the image is as written.
    WriteText(dir / "cam.yaml", "%YAML:1.0\nfx: 80\nfy: 80\ncx: 31.5\ncy: 23.5\nwidth: 64\nheight: 48\n");
    options.calibration_yaml = dir / "cam.yaml";
    auto raw = OpenDataset(path, options);
    ASSERT_TRUE(raw->Next(&frame));
    EXPECT_LE(cv::norm(frame.left, RandomImage(64, 48, 1), cv::NORM_INF), 1) << encoding;
  }
}

TEST(BagDataset, CompressedImagesAndTheOnlyImageTopicByDefault) {
  TempDir dir;
  WriteBag(dir / "c.bag", "", true, false, false);
  DatasetOptions options;
  WriteText(dir / "cam.yaml", "%YAML:1.0\nfx: 80\nfy: 80\ncx: 31.5\ncy: 23.5\nwidth: 64\nheight: 48\n");
  options.calibration_yaml = dir / "cam.yaml";
  auto bag = OpenDataset(dir / "c.bag", options);
  EXPECT_EQ(bag->size(), 4u);
  Frame frame;
  ASSERT_TRUE(bag->Next(&frame));
  EXPECT_EQ(cv::norm(frame.left, RandomImage(64, 48, 0), cv::NORM_INF), 0);
}

TEST(BagDataset, StereoPairRectifiedWithTheCameraInfos) {
  TempDir dir;
  WriteBag(dir / "s.bag", "mono8", false, true, true);
  DatasetOptions options;
  options.topic = "/cam0/image_raw";
  options.right_topic = "/cam1/image_raw";
  auto bag = OpenDataset(dir / "s.bag", options);
  EXPECT_TRUE(bag->is_stereo());
  EXPECT_NEAR(bag->rig().baseline, 0.12, 1e-12);
  Frame frame;
  ASSERT_TRUE(bag->Next(&frame));
  EXPECT_EQ(frame.right.size(), cv::Size(64, 48));
}

TEST(BagDataset, ErrorsListTheBagsTopics) {
  TempDir dir;
  WriteBag(dir / "m.bag", "mono8", false, false, false);
  DatasetOptions options;
  options.topic = "/camera/image";
  const std::string missing = ErrorOf([&] { OpenDataset(dir / "m.bag", options); });
  EXPECT_THAT(missing, HasSubstr("has no image topic '/camera/image'"));
  EXPECT_THAT(missing, HasSubstr("/cam0/image_raw (sensor_msgs/Image)"));
  EXPECT_THAT(missing, HasSubstr("/imu (sensor_msgs/CameraInfo)"));
  options.topic = "/cam0/image_raw";
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "m.bag", options); }),
              HasSubstr("give the calibration with --calibration"));
  {
    rosbag::Bag bag(dir / "no_images.bag", rosbag::bagmode::Write);
    bag.write("/imu", ros::Time(1, 0), sensor_msgs::CameraInfo());
  }
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "no_images.bag"); }),
              HasSubstr("has no images (no sensor_msgs/Image or sensor_msgs/CompressedImage "
                        "topic); its topics: /imu"));
  WriteText(dir / "text.bag", "not a bag at all");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "text.bag"); }),
              HasSubstr("cannot read the ROS bag"));
}

#endif  // DALA_HAVE_ROSBAG

}  // namespace
}  // namespace dala
