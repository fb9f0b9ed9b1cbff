// A real clip through the video path: KITTI 06 frames 0-50 (../shared/data) encoded side by side
// into a video by cv::VideoWriter, run by `dala run VIDEO --stereo_layout side_by_side`, gives an
// ATE within 1.3x of the same frames read as PNG (the KITTI folder).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/io/kitti_dataset.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

nlohmann::json DalaRun(const std::string& input, const std::string& extra,
                       const std::string& out) {
  std::filesystem::remove_all(out);
  return testing::RunDalaForReport("run " + input + " --config " + DALA_SOURCE_DIR +
                                       "/configs/kitti.yaml --progress=false --out " + out + " " +
                                       extra,
                                   out);
}

TEST(VideoClipE2e, KittiClipAsVideoWithinOnePointThreeTimesThePngAte) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  testing::TempDir dir;
  const std::string clip = testing::SharedDataDir() + "/kitti06_0000-0050";
  // The clip's calibration in dala's own format (a rectified pair).
  const auto P0 = ReadKittiProjection(clip + "/calib.txt", 0);
  const auto P1 = ReadKittiProjection(clip + "/calib.txt", 1);
  ASSERT_TRUE(P0 && P1);
  const cv::Mat first = cv::imread(clip + "/image_0/000000.png", cv::IMREAD_GRAYSCALE);
  {
    std::ofstream calib(dir / "kitti06.yaml");
    calib.precision(12);
    calib << "%YAML:1.0\nfx: " << (*P0)(0, 0) << "\nfy: " << (*P0)(1, 1) << "\ncx: " << (*P0)(0, 2)
          << "\ncy: " << (*P0)(1, 2) << "\nwidth: " << first.cols << "\nheight: " << first.rows
          << "\nbaseline: " << -(*P1)(0, 3) / (*P1)(0, 0) << "\n";
  }
  // Encode: left | right, 10 fps, MPEG-4 part 2 in mp4 (lossy, what VideoWriter writes here).
  const std::string video = dir / "kitti06.mp4";
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 10.0,
                           cv::Size(2 * first.cols, first.rows), /*isColor=*/false);
    ASSERT_TRUE(writer.isOpened()) << "VideoWriter cannot write mp4v here";
    for (int i = 0; i <= 50; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", i);
      cv::Mat pair;
      cv::hconcat(cv::imread(clip + "/image_0/" + name, cv::IMREAD_GRAYSCALE),
                  cv::imread(clip + "/image_1/" + name, cv::IMREAD_GRAYSCALE), pair);
      writer.write(pair);
    }
  }
  const nlohmann::json png = DalaRun(clip, "", dir / "png");
  const nlohmann::json mp4 = DalaRun(video,
                                     "--calibration " + (dir / "kitti06.yaml") +
                                         " --stereo_layout side_by_side --ground_truth " + clip +
                                         "/poses.txt",
                                     dir / "video");
  ASSERT_FALSE(png.is_discarded());
  ASSERT_FALSE(mp4.is_discarded());
  EXPECT_EQ(mp4["dataset"]["format"], "video");
  EXPECT_EQ(mp4["summary"]["frames_with_pose"].get<int>(), 51);
  const double ate_png = png["summary"]["ate"]["rmse"].get<double>();
  const double ate_video = mp4["summary"]["ate"]["rmse"].get<double>();
  std::cout << "[ measured ] KITTI 06 0-50 stereo BA: ATE PNG " << ate_png << " m, mp4v video "
            << ate_video << " m (" << std::filesystem::file_size(video) / 1024
            << " KiB), ratio " << ate_video / ate_png << std::endl;
  EXPECT_LT(ate_video, 1.3 * ate_png);
}

}  // namespace
}  // namespace dala
