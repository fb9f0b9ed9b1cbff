#include "core/sim/dataset_writer.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/io/text_lines.h"
#include "core/io/trajectory_io.h"
#include "tests/test_util.h"

namespace dala::sim {
namespace {

namespace fs = std::filesystem;

SimOptions TinyOptions() {
  SimOptions o;
  o.preset = "flight";
  o.frames = 3;
  o.width = 160;
  o.height = 120;
  o.fx = o.fy = 100;
  o.baseline = 0.5;
  o.texture_size = 128;
  return o;
}

std::vector<double> CalibRow(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) == 0) {
      std::istringstream is(line.substr(key.size() + 1));
      std::vector<double> v;
      double x;
      while (is >> x) v.push_back(x);
      return v;
    }
  }
  return {};
}

TEST(DatasetWriterTest, WritesKittiLikeStereoFolder) {
  testing::TempDir dir;
  const SimOptions o = TinyOptions();
  SyntheticDatasetOutputs outputs;
  outputs.points = true;
  outputs.odometry = true;
  int progress_calls = 0;
  outputs.progress_every = 2;
  outputs.progress = [&](size_t, size_t total) {
    ++progress_calls;
    EXPECT_EQ(total, 3u);
  };
  WriteSyntheticDataset(o, dir.path(), outputs);
  EXPECT_EQ(progress_calls, 2);  // After frame 2 and at the end.
  for (int i = 0; i < 3; ++i) {
    for (int cam : {0, 1}) {
      const std::string p =
          dir.path() + "/image_" + std::to_string(cam) + "/00000" + std::to_string(i) + ".png";
      const cv::Mat img = cv::imread(p, cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(img.empty()) << p;
      EXPECT_EQ(img.type(), CV_8UC1);
      EXPECT_EQ(img.cols, 160);
    }
  }
  EXPECT_FALSE(fs::exists(dir / "image_0/000003.png"));
  // The image on disk is the rendered frame.
  const SyntheticSequence seq(o);
  EXPECT_EQ(cv::norm(cv::imread(dir / "image_1/000002.png", cv::IMREAD_UNCHANGED),
                     seq.Render(2).right, cv::NORM_INF),
            0);
  // calib.txt: P0 = K [I | 0], P1 = K [I | (-b, 0, 0)].
  const auto p0 = CalibRow(dir / "calib.txt", "P0");
  const auto p1 = CalibRow(dir / "calib.txt", "P1");
  ASSERT_EQ(p0.size(), 12u);
  ASSERT_EQ(p1.size(), 12u);
  EXPECT_DOUBLE_EQ(p0[0], 100);
  EXPECT_DOUBLE_EQ(p0[2], 79.5);
  EXPECT_DOUBLE_EQ(p0[6], 59.5);
  EXPECT_DOUBLE_EQ(p0[3], 0);
  EXPECT_DOUBLE_EQ(p1[3], -100 * 0.5);
  EXPECT_EQ(CalibRow(dir / "calib.txt", "P3").size(), 12u);
  // poses.txt + times.txt give the ground truth.
  Trajectory poses = ReadTrajectory(dir / "poses.txt", TrajectoryFormat::kKitti);
  ApplyTimes(dir / "times.txt", &poses);
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses.poses[2].t_ns, 200000000);
  EXPECT_POSE_NEAR(poses.poses[2].T_w_c, seq.T_w_c0(2), 1e-6);
  // Odometry (TUM) and points.
  const Trajectory odom = ReadTrajectory(dir / "odometry.txt");
  EXPECT_EQ(odom.size(), 3u);
  EXPECT_POSE_NEAR(odom.poses[0].T_w_c, seq.T_w_c0(0), 1e-6);
  std::ifstream ply(dir / "points.ply");
  std::string magic;
  ply >> magic;
  EXPECT_EQ(magic, "ply");
  // The marker.
  cv::FileStorage marker(dir / "synth.yaml", cv::FileStorage::READ);
  ASSERT_TRUE(marker.isOpened());
  EXPECT_EQ(static_cast<std::string>(marker["format"]), "dala-synthetic");
  EXPECT_EQ(static_cast<int>(marker["version"]), 1);
  EXPECT_EQ(static_cast<std::string>(marker["preset"]), "flight");
  EXPECT_EQ(static_cast<int>(marker["frames"]), 3);
  EXPECT_EQ(static_cast<int>(marker["seed"]), 1);
  EXPECT_EQ(static_cast<int>(marker["width"]), 160);
  EXPECT_DOUBLE_EQ(static_cast<double>(marker["baseline"]), 0.5);
  EXPECT_DOUBLE_EQ(static_cast<double>(marker["fps"]), 10.0);
  // No temporary files are left behind.
  for (const auto& e : fs::recursive_directory_iterator(dir.path())) {
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  }
}

TEST(DatasetWriterTest, MonoHasNoRightImagesAndZeroBaseline) {
  testing::TempDir dir;
  SimOptions o = TinyOptions();
  o.stereo = false;
  WriteSyntheticDataset(o, dir.path(), false);
  EXPECT_TRUE(fs::exists(dir / "image_0/000000.png"));
  EXPECT_FALSE(fs::exists(dir / "image_1"));
  EXPECT_FALSE(fs::exists(dir / "points.ply"));
  EXPECT_FALSE(fs::exists(dir / "odometry.txt"));
  EXPECT_DOUBLE_EQ(CalibRow(dir / "calib.txt", "P1")[3], 0.0);
}

TEST(DatasetWriterTest, InvalidOptionsThrowBeforeWriting) {
  testing::TempDir dir;
  SimOptions o = TinyOptions();
  o.preset = "nope";
  EXPECT_THROW(WriteSyntheticDataset(o, dir / "out", false), Error);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(DatasetWriterTest, CommandLineWritesAFolderAndRejectsBadFlags) {
  testing::TempDir dir;
  const std::string ok = std::string(DALA_BINARY) + " synth --out " + (dir / "seq") +
                         " --preset rotation --frames 2 --width 96 --height 64 --fx 60 --fy 60"
                         " --mono --points 2>/dev/null";
  EXPECT_EQ(std::system(ok.c_str()), 0);
  EXPECT_TRUE(fs::exists(dir / "seq/image_0/000001.png"));
  EXPECT_TRUE(fs::exists(dir / "seq/points.ply"));
  EXPECT_TRUE(fs::exists(dir / "seq/synth.yaml"));
  EXPECT_FALSE(fs::exists(dir / "seq/image_1"));
  const std::string bad =
      std::string(DALA_BINARY) + " synth --out " + (dir / "bad") + " --preset nope 2>/dev/null";
  EXPECT_EQ(WEXITSTATUS(std::system(bad.c_str())), 2);
  const std::string no_out = std::string(DALA_BINARY) + " synth 2>/dev/null";
  EXPECT_EQ(WEXITSTATUS(std::system(no_out.c_str())), 2);
}

}  // namespace
}  // namespace dala::sim
