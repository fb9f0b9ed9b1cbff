// Video files (core/io/video_dataset.h), written by the test with cv::VideoWriter.
#include "core/io/video_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/io/dataset.h"
#include "tests/core/io/dataset_fixtures.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ErrorOf;
using ::testing::HasSubstr;
using testing::TempDir;
using testing::WriteText;

constexpr const char* kCalibration =
    "%YAML:1.0\nfx: 80\nfy: 80\ncx: 63.5\ncy: 47.5\nwidth: 128\nheight: 96\nbaseline: 0.2\n";

// Frame i: a smooth pattern shifted by i pixels (survives lossy codecs), colour.
cv::Mat Pattern(int width, int height, int i) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const uchar g = static_cast<uchar>(128 + 100 * std::sin(0.2 * (x + i)) * std::cos(0.15 * y));
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(g, g, g);
    }
  }
  return image;
}

// Writes `frames` frames; false when this OpenCV cannot write the codec.
bool WriteVideo(const std::string& path, const char* fourcc, int width, int height, int frames,
                double fps = 10) {
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc(fourcc[0], fourcc[1], fourcc[2], fourcc[3]),
                         fps, cv::Size(width, height));
  if (!writer.isOpened()) return false;
  for (int i = 0; i < frames; ++i) writer.write(Pattern(width, height, i));
  return true;
}

TEST(VideoDataset, MonoFramesTimesAndRange) {
  TempDir dir;
  ASSERT_TRUE(WriteVideo(dir / "clip.avi", "MJPG", 128, 96, 12));
  WriteText(dir / "cam.yaml", kCalibration);
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  EXPECT_EQ(DetectDatasetFormat(dir / "clip.avi"), DatasetFormat::kVideo);
  auto video = OpenDataset(dir / "clip.avi", options);
  EXPECT_EQ(video->format(), DatasetFormat::kVideo);
  EXPECT_EQ(video->size(), 12u);
  EXPECT_FALSE(video->is_stereo());
  EXPECT_EQ(video->rig().baseline, 0);
  Frame frame;
  std::vector<int64_t> times;
  while (video->Next(&frame)) {
    EXPECT_EQ(frame.left.type(), CV_8UC1);
    EXPECT_EQ(frame.left.size(), cv::Size(128, 96));
    times.push_back(frame.t_ns);
  }
  ASSERT_EQ(times.size(), 12u);
  EXPECT_NEAR(times[3] - times[2], 100000000, 1000000);  // 10 fps from the container.

  options.first_frame = 4;
  options.max_frames = 3;
  options.fps = 20;
  auto range = OpenDataset(dir / "clip.avi", options);
  EXPECT_EQ(range->size(), 3u);
  ASSERT_TRUE(range->Next(&frame));
  EXPECT_EQ(frame.id.value, 4);
  EXPECT_EQ(frame.t_ns, 200000000);  // 4 / 20 Hz.
  // The decoded frame is frame 4 of the file (the lossy codec: compare loosely).
  cv::Mat expected;
  cv::cvtColor(Pattern(128, 96, 4), expected, cv::COLOR_BGR2GRAY);
  EXPECT_LT(cv::norm(frame.left, expected, cv::NORM_L1) / frame.left.total(), 3.0);
  range->Rewind();
  ASSERT_TRUE(range->Next(&frame));
  EXPECT_EQ(frame.id.value, 4);
}

TEST(VideoDataset, SideBySideStereo) {
  TempDir dir;
  ASSERT_TRUE(WriteVideo(dir / "pair.avi", "MJPG", 256, 96, 3));
  WriteText(dir / "cam.yaml", kCalibration);
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  // Without the layout, the frame size is not the calibration's: the error says what to do.
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "pair.avi", options); }),
              HasSubstr("--stereo_layout side_by_side"));
  options.stereo_layout = "side_by_side";
  auto video = OpenDataset(dir / "pair.avi", options);
  EXPECT_TRUE(video->is_stereo());
  EXPECT_DOUBLE_EQ(video->rig().baseline, 0.2);
  Frame frame;
  ASSERT_TRUE(video->Next(&frame));
  EXPECT_EQ(frame.left.size(), cv::Size(128, 96));
  EXPECT_EQ(frame.right.size(), cv::Size(128, 96));
  options.force_mono = true;
  auto mono = OpenDataset(dir / "pair.avi", options);
  EXPECT_FALSE(mono->is_stereo());
  ASSERT_TRUE(mono->Next(&frame));
  EXPECT_EQ(frame.left.size(), cv::Size(128, 96));
}

TEST(VideoDataset, CodecsThisOpenCvWrites) {
  // Which codecs cv::VideoWriter can write here (the clip test encodes with the first), and
  // that the reader decodes each of them.
  TempDir dir;
  WriteText(dir / "cam.yaml", kCalibration);
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  for (const auto& [fourcc, ext] : {std::pair{"FFV1", "mkv"}, std::pair{"mp4v", "mp4"},
                                    std::pair{"MJPG", "avi"}, std::pair{"avc1", "mp4"},
                                    std::pair{"XVID", "avi"}, std::pair{"mp4v", "mov"}}) {
    const std::string path = dir / (std::string("c_") + fourcc + "." + ext);
    if (!WriteVideo(path, fourcc, 128, 96, 5)) {
      std::cout << "[ codec    ] " << fourcc << " ." << ext << ": cannot be written here\n";
      continue;
    }
    auto video = OpenDataset(path, options);
    std::cout << "[ codec    ] " << fourcc << " ." << ext << ": written and read, "
              << video->size() << " frames\n";
    EXPECT_EQ(video->size(), 5u) << path;
  }
}

TEST(VideoDataset, BadInputSaysWhetherTheFileOrTheCodec) {
  TempDir dir;
  WriteText(dir / "cam.yaml", kCalibration);
  DatasetOptions options;
  options.calibration_yaml = dir / "cam.yaml";
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "none.mp4", options); }), HasSubstr("missing"));
  WriteText(dir / "empty.mp4", "");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "empty.mp4", options); }),
              HasSubstr("is empty (0 bytes): the file is the problem"));
  WriteText(dir / "text.mp4", "this is not a video, just some text that is long enough\n");
  const std::string text = ErrorOf([&] { OpenDataset(dir / "text.mp4", options); });
  EXPECT_THAT(text, HasSubstr("cannot open video"));
  EXPECT_THAT(text, HasSubstr("the file is the problem"));
  ASSERT_TRUE(WriteVideo(dir / "clip.avi", "MJPG", 128, 96, 2));
  options.calibration_yaml.clear();
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "clip.avi", options); }),
              HasSubstr("needs its camera calibration"));
  WriteText(dir / "big.yaml", "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 640\nheight: 480\n");
  options.calibration_yaml = dir / "big.yaml";
  const std::string size = ErrorOf([&] { OpenDataset(dir / "clip.avi", options); });
  EXPECT_THAT(size, HasSubstr("128x96 frames, but the calibration"));
  EXPECT_THAT(size, HasSubstr("640x480"));
}

}  // namespace
}  // namespace dala
