// Stereo and one camera on real images that change as a real drive's do, with the recorded
// ground truth: KITTI 06 0-50 with an exposure per camera and frame, and a stop. The folder is of
// the kinds `scripts/stressed_images.py --kind gain_per_camera` and `--kind stop` make, both in
// one (this file draws its own noise with std::mt19937, so the pixels differ from the script's):
//  - every image is multiplied by exp(N(0, 0.3^2)), drawn per camera and frame (cameras that
//    expose on their own: the stereo and temporal matches compare patches of other brightness);
//  - at frame 25 the car stands still for 15 frames: that image pair repeated, the times
//    renumbered at 10 Hz; every image gets fresh N(0, 2^2) sensor noise, so the copies differ.
// std::normal_distribution's draws depend on the standard library (libstdc++ here), so another
// one makes other images and another measured ATE, well within the 1.5x bounds.
// Measured values: docs/results.md, "stop 59".
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/io/trajectory_io.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

constexpr int kStopAt = 25;      // The frame at which the car stops...
constexpr int kStopFrames = 15;  // ...and the frames it stands still after it.

// KITTI 06 0-50 with an exposure per camera and frame and a stop (see the top of the file), as
// a KITTI folder in `dst`; output frame j shows recorded frame SourceFrame(j).
int SourceFrame(int j) { return j <= kStopAt ? j : std::max(kStopAt, j - kStopFrames); }

std::string StressedKitti(const std::filesystem::path& dst) {
  namespace fs = std::filesystem;
  const fs::path src = fs::path(testing::SharedDataDir()) / "kitti06_0000-0050";
  fs::create_directories(dst / "image_0");
  fs::create_directories(dst / "image_1");
  fs::copy_file(src / "calib.txt", dst / "calib.txt");
  std::vector<std::string> poses;
  std::ifstream poses_in(src / "poses.txt");
  for (std::string line; std::getline(poses_in, line);) {
    if (!line.empty()) poses.push_back(line);
  }
  if (poses.size() != 51u) {
    ADD_FAILURE() << src / "poses.txt"
                  << " has " << poses.size() << " poses, not 51";
    return dst.string();
  }
  std::mt19937 rng(59);
  std::normal_distribution<double> log_gain(0.0, 0.3);
  std::ofstream poses_out(dst / "poses.txt"), times_out(dst / "times.txt");
  const int frames = static_cast<int>(poses.size()) + kStopFrames;
  for (int j = 0; j < frames; ++j) {
    const int i = SourceFrame(j);
    poses_out << poses[i] << "\n";
    char time[32];
    std::snprintf(time, sizeof(time), "%e\n", 0.1 * j);
    times_out << time;
    char file[16];
    std::snprintf(file, sizeof(file), "%06d.png", i);
    char out_file[16];
    std::snprintf(out_file, sizeof(out_file), "%06d.png", j);
    for (const char* cam : {"image_0", "image_1"}) {
      const cv::Mat image = cv::imread((src / cam / file).string(), cv::IMREAD_GRAYSCALE);
      if (image.empty()) {
        ADD_FAILURE() << "cannot read " << src / cam / file;
        return dst.string();
      }
      cv::Mat noise(image.size(), CV_32F);
      cv::RNG noise_rng(rng());
      noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
      cv::Mat stressed;
      image.convertTo(stressed, CV_32F, std::exp(log_gain(rng)));
      cv::Mat out;
      cv::Mat(stressed + noise).convertTo(out, CV_8U);  // Rounded and clipped to [0, 255].
      EXPECT_TRUE(cv::imwrite((dst / cam / out_file).string(), out)) << out_file;
    }
  }
  return dst.string();
}

struct StressedRun {
  nlohmann::json summary;
  Trajectory trajectory;
};

StressedRun RunStressed(const std::string& data, const std::string& out, const std::string& mode) {
  const nlohmann::json report = testing::RunDalaForReport(
      "run " + data + " --mode " + mode + " --progress=false --out " + out, out);
  StressedRun run;
  if (!report.is_discarded()) run.summary = report["summary"];
  if (std::filesystem::exists(out + "/trajectory.txt")) {
    run.trajectory = ReadTrajectory(out + "/trajectory.txt", TrajectoryFormat::kTum);
  }
  return run;
}

// The camera's travel while the car stands still (output frames kStopAt .. kStopAt +
// kStopFrames, one recorded pose), against its mean step while it moves: 0 for a still estimate,
// in the run's own unit (one camera's is arbitrary).
double StillTravelInSteps(const Trajectory& t) {
  double moving = 0.0, still = 0.0;
  int moving_steps = 0;
  for (size_t k = 1; k < t.size(); ++k) {
    const int j = static_cast<int>(std::lround(t.poses[k].t_ns * 1e-8));
    const int j_prev = static_cast<int>(std::lround(t.poses[k - 1].t_ns * 1e-8));
    const double step =
        (t.poses[k].T_w_c.translation() - t.poses[k - 1].T_w_c.translation()).norm();
    if (SourceFrame(j) == SourceFrame(j_prev)) {
      still += step;
    } else {
      moving += step / (j - j_prev);
      ++moving_steps;
    }
  }
  return moving_steps > 0 ? still / (moving / moving_steps) : 1e9;
}

void ExpectHolds(const StressedRun& run, const std::string& label, double best_ate) {
  const nlohmann::json& s = run.summary;
  ASSERT_TRUE(s.contains("ate")) << label << ": no evaluation";
  const int frames = 51 + kStopFrames;
  const double ate = s["ate"]["rmse"].get<double>();
  const double still = StillTravelInSteps(run.trajectory);
  std::cout << "[ measured ] " << label << ": " << s["frames_with_pose"].get<int>() << " of "
            << s["frames"].get<int>() << " frames with a pose, ATE " << ate
            << " m, travel while stopped " << still << " of a moving step" << std::endl;
  EXPECT_EQ(s["frames"].get<int>(), frames) << label;
  EXPECT_EQ(s["frames_with_pose"].get<int>(), frames) << label;
  EXPECT_EQ(static_cast<int>(run.trajectory.size()), frames) << label;
  // 15 still frames: their estimated travel together stays below a twentieth of one moving step.
  EXPECT_LT(still, 0.05) << label;
  testing::ExpectWithinBound(label + ", ATE", ate, best_ate, "m");
}

// Stereo (SE(3) ATE after the global BA) and one camera (Sim(3) ATE) from frame 0: every frame
// has a pose, the stop is held still (measured: the 15 still frames travel 0.028 / 0.027 of a
// moving step together), the ATE bound 1.5x the measured (0.0198 / 0.0241 m). Without the
// stresses the same runs give 0.0253 / 0.0226 m.
TEST(KittiExposureE2e, ExposurePerCameraAndAStopKeepEveryFrameAndTheStopStill) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  const testing::TempDir tmp;
  const std::string data = StressedKitti(std::filesystem::path(tmp.path()) / "data");
  if (HasFailure()) return;  // No complete folder to run on.
  ExpectHolds(RunStressed(data, tmp.path() + "/stereo", "stereo"),
              "ba/stereo KITTI 06 0-50, exposure per camera and frame, a 15-frame stop", 0.0198);
  ExpectHolds(RunStressed(data, tmp.path() + "/mono", "mono"),
              "ba/mono KITTI 06 0-50, exposure per camera and frame, a 15-frame stop", 0.0241);
}

}  // namespace
}  // namespace dala
