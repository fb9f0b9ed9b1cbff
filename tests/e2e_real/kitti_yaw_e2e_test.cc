// One camera on real images through fast rotations, with exact ground truth: KITTI 06 0-50's left
// images turned about the camera centre by an added yaw (a homography, exact for a rotation),
// the recorded poses turned by the same yaw.
//
// The virtual camera keeps KITTI's focal length (707.09 px) on a 720 x 300 image centred in the
// recorded one, so that a yaw of up to 9 deg stays inside the recorded view. The yaw of frame i is
// theta_i = A sin(2 pi i / P); a pixel of the virtual image comes from the recorded pixel
// K R_y(theta_i) K_v^-1 (u, v, 1) (R_y: about the camera's y axis, down), and the camera-to-world
// rotation of frame i is R_w_c R_y(theta_i).
//
// - A = 4 deg, P = 8 frames (up to 2.8 deg per frame), from frame 0: the map starts from frames
//   0 and 1, and the frame after them finds only 4 of the pair's 73 points. Before the pair's
//   current frame counted as the map's last tracked frame, neither the keyframe bridge nor the
//   re-initialisation after ba.mono_reinit_after_lost_frames could start (both continue from the
//   last tracked frame) and the other 49 frames were lost. Now the next frames are bridged from
//   the pair's keyframe: 49 of 51 frames with a pose, Sim(3) ATE 0.0843 m (docs/results.md,
//   "stop 58"); bound 1.5x.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

constexpr int kWidth = 720;
constexpr int kHeight = 300;

// KITTI 06 0-50's left images with the added yaw, in a KITTI folder (image_0 only).
std::string YawedKitti(double amplitude_deg, int period_frames) {
  namespace fs = std::filesystem;
  const fs::path src = fs::path(testing::SharedDataDir()) / "kitti06_0000-0050";
  std::ostringstream name;
  name << "dala_kitti_yaw_" << amplitude_deg << "_" << period_frames;
  const fs::path dst = fs::path(::testing::TempDir()) / name.str();
  fs::remove_all(dst);
  fs::create_directories(dst / "image_0");
  fs::copy_file(src / "times.txt", dst / "times.txt");

  std::ifstream calib_in(src / "calib.txt");
  std::string label;
  Eigen::Matrix<double, 3, 4> P0;
  calib_in >> label;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) calib_in >> P0(r, c);
  }
  const Eigen::Matrix3d K = P0.leftCols<3>();
  Eigen::Matrix3d K_v = K;
  K_v(0, 2) = (kWidth - 1) / 2.0;
  K_v(1, 2) = K(1, 2) - (370 - kHeight) / 2.0;
  std::ofstream calib_out(dst / "calib.txt");
  calib_out.precision(12);
  for (int k = 0; k < 4; ++k) {
    calib_out << "P" << k << ":";
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) calib_out << " " << (c < 3 ? K_v(r, c) : 0.0);
    }
    calib_out << "\n";
  }

  std::ifstream poses_in(src / "poses.txt");
  std::ofstream poses_out(dst / "poses.txt");
  poses_out.precision(12);
  for (int i = 0;; ++i) {
    Eigen::Matrix<double, 3, 4> T;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) poses_in >> T(r, c);
    }
    if (!poses_in) break;
    const double theta = amplitude_deg * M_PI / 180.0 * std::sin(2.0 * M_PI * i / period_frames);
    const Eigen::Matrix3d R_y = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).matrix();
    T.leftCols<3>() = T.leftCols<3>() * R_y;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) poses_out << (r + c ? " " : "") << T(r, c);
    }
    poses_out << "\n";

    char file[16];
    std::snprintf(file, sizeof(file), "%06d.png", i);
    const cv::Mat image = cv::imread((src / "image_0" / file).string(), cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(image.empty()) << file;
    cv::Mat virtual_to_recorded;
    cv::eigen2cv(Eigen::Matrix3d(K * R_y * K_v.inverse()), virtual_to_recorded);
    cv::Mat turned;
    cv::warpPerspective(image, turned, virtual_to_recorded, cv::Size(kWidth, kHeight),
                        cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
    EXPECT_TRUE(cv::imwrite((dst / "image_0" / file).string(), turned)) << file;
  }
  return dst.string();
}

// dala run --mode mono on `data` with `extra` options: report.json's summary.
nlohmann::json RunMono(const std::string& data, const std::string& name, const std::string& extra) {
  const std::string out = data + "_" + name;
  std::filesystem::remove_all(out);
  const testing::DalaCliResult r =
      testing::RunDala("run " + data + " --mode mono --progress=false --out " + out + extra, out);
  EXPECT_EQ(r.status, 0) << r.log();
  std::ifstream in(out + "/report.json");
  const nlohmann::json report = nlohmann::json::parse(in, nullptr, false);
  EXPECT_FALSE(report.is_discarded()) << "no report.json in " << out;
  return report.is_discarded() ? nlohmann::json() : report["summary"];
}

TEST(KittiYawMonoE2e, AMapWhosePairIsNotFoundAgainIsBridgedNotLost) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  const nlohmann::json s = RunMono(YawedKitti(4.0, 8), "defaults", "");
  ASSERT_EQ(s.value("frames", 0), 51);
  const int with_pose = s["frames_with_pose"].get<int>();
  ASSERT_TRUE(s.contains("ate")) << "no evaluation: " << with_pose << " frames with a pose";
  const double ate = s["ate"]["rmse"].get<double>();
  std::cout << "[ measured ] ba/mono KITTI 06 0-50 turned by 4 deg sin(2 pi i / 8): " << with_pose
            << " of 51 frames with a pose, Sim(3) ATE " << ate << " m" << std::endl;
  EXPECT_GE(with_pose, 47);
  testing::ExpectWithinBound("ba/mono KITTI 06 0-50 with an added yaw (4 deg, 8 frames), ATE", ate,
                             0.0843, "m");
}

// keyframe.mono_parallax_without_rotation (experimental): the parallax criterion counts only the
// image motion the rotation since the keyframe does not explain, so the turns make fewer
// keyframes. Measured on the same turned images from frame 0: 38 keyframes with the defaults, 26
// with it, Sim(3) ATE 0.0821 m (bound 1.5x), every frame after the first pair's next posed as
// with the defaults.
TEST(KittiYawMonoE2e, ParallaxWithoutRotationMakesFewerKeyframesInTurns) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  const std::string data = YawedKitti(4.0, 8);
  const nlohmann::json defaults = RunMono(data, "defaults", "");
  const nlohmann::json unrotated =
      RunMono(data, "unrotated", " --set keyframe.mono_parallax_without_rotation=1");
  ASSERT_TRUE(defaults.contains("ate") && unrotated.contains("ate"));
  const int before = defaults["keyframes"].get<int>(), after = unrotated["keyframes"].get<int>();
  const double ate = unrotated["ate"]["rmse"].get<double>();
  std::cout << "[ measured ] ba/mono KITTI 06 0-50 turned by 4 deg sin(2 pi i / 8): " << before
            << " keyframes with the defaults, " << after
            << " with the parallax without rotation, Sim(3) ATE " << ate << " m" << std::endl;
  EXPECT_LT(after, 0.8 * before);
  EXPECT_GE(unrotated["frames_with_pose"].get<int>(), 47);
  testing::ExpectWithinBound(
      "ba/mono KITTI 06 0-50 with an added yaw (4 deg, 8 frames), parallax without rotation, ATE",
      ate, 0.0821, "m");
}

}  // namespace
}  // namespace dala
