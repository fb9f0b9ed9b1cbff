// `dala run --video`: FrameVideo draws each frame and writes a video that OpenCV reads back with
// every frame, moved into place only when closed.
#include "tools/report/frame_video.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/videoio.hpp>
#include <string>

#include "core/error.h"
#include "tests/test_util.h"

namespace dala::report {
namespace {

TEST(FrameVideo, WritesEveryFrameAndMovesTheFileIntoPlaceOnClose) {
  testing::TempDir dir;
  const std::string path = dir / "frames.mp4";
  std::string written;
  {
    FrameVideo video(path);
    for (int i = 0; i < 6; ++i) {
      cv::Mat left(121, 161, CV_8UC1, cv::Scalar(40 * i));  // Odd sizes: made even.
      FrameMeasurement m;
      FeatureObservation o;
      o.uv = Eigen::Vector2d(50 + i, 60);
      o.u_right = 40.0 + i;
      o.track_length = i + 1;
      m.observations.push_back(o);
      FrameStats s;
      s.frame = FrameId{i};
      s.t_ns = i * 100000000LL;
      s.status = TrackingStatus::kTracking;
      s.keyframe = i % 3 == 0;
      Pose T = Pose::Identity();
      T.translation() = Eigen::Vector3d(0, 0, i);
      video.Add(left, m, s, T);
      // Nothing under the final name while the video is being written.
      EXPECT_FALSE(std::filesystem::exists(path));
    }
    written = video.Close();
  }
  ASSERT_FALSE(written.empty());
  ASSERT_TRUE(std::filesystem::exists(written)) << written;
  cv::VideoCapture capture(written);
  ASSERT_TRUE(capture.isOpened());
  int frames = 0;
  cv::Mat picture;
  while (capture.read(picture)) {
    ++frames;
    EXPECT_EQ(picture.cols % 2, 0);
    EXPECT_EQ(picture.rows % 2, 0);
    EXPECT_GE(picture.cols, 161);
  }
  EXPECT_EQ(frames, 6);
  // Only the video is left in the folder (no temporary).
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(FrameVideo, NamesTheFlagForAFileItCannotWrite) {
  testing::TempDir dir;
  EXPECT_NE(testing::ErrorOf([&] { FrameVideo video(dir / "frames.gif"); }).find(".mp4"),
            std::string::npos);
  EXPECT_NE(testing::ErrorOf([&] {
              FrameVideo video(dir / "no/such/folder/frames.mp4");
            }).find("does not exist"),
            std::string::npos);
}

}  // namespace
}  // namespace dala::report
