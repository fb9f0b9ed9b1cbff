// `dala fuse` end to end: the binary (DALA_BINARY) on run folders and trajectory files.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/trajectory_io.h"
#include "tests/core/eval/eval_test_util.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;

// A `dala run` folder: trajectory.txt and the report.json line that says its scale.
void WriteRunFolder(const std::string& dir, const Trajectory& trajectory,
                    const std::string& scale_source) {
  std::filesystem::create_directories(dir);
  WriteTrajectoryTum(dir + "/trajectory.txt", trajectory);
  std::ofstream(dir + "/report.json")
      << nlohmann::json{{"summary", {{"scale_source", scale_source}}}};
}

class FuseCli : public ::testing::Test {
 protected:
  testing::TempDir dir_;
  const Trajectory truth_ = testing::HelixTrajectory(50);
};

// Three one-camera runs of the same motion, each in its own world and unit: the fusion is the
// first run, and the report says which alignment and how far apart the runs were.
TEST_F(FuseCli, OneCameraRunsFuseBySimilarity) {
  WriteRunFolder(dir_ / "r0", truth_, "arbitrary (monocular)");
  WriteRunFolder(dir_ / "r1", testing::Transformed(truth_, 3.0, {0.1, -0.3, 0.7}, {1, 2, 3}),
                 "arbitrary (monocular)");
  WriteTrajectoryTum(dir_ / "r2.txt", testing::Transformed(truth_, 0.5, {0.1, -0.3, 0.7},
                                                           {-4, 0, 1}));  // A file, not a folder.
  const auto r = testing::RunDala("fuse " + dir_ / "r0" + " " + dir_ / "r1" + " " +
                                      dir_ / "r2.txt" + " --out " + dir_ / "fused",
                                  dir_ / "log");
  ASSERT_EQ(r.status, 0) << r.log();
  EXPECT_THAT(r.out, HasSubstr("fused       3 runs, 50 poses (50 in every run), aligned by sim3"));
  const Trajectory fused = ReadTrajectory(dir_ / "fused/trajectory.txt");
  ASSERT_EQ(fused.size(), truth_.size());
  for (size_t i = 0; i < fused.size(); ++i) {
    EXPECT_LT((fused.poses[i].T_w_c.translation() - truth_.poses[i].T_w_c.translation()).norm(),
              1e-6);
  }
  EXPECT_EQ(ReadTrajectory(dir_ / "fused/trajectory_kitti.txt").size(), truth_.size());
  std::ifstream report(dir_ / "fused/fusion.json");
  const nlohmann::json j = nlohmann::json::parse(report);
  EXPECT_EQ(j.at("alignment").get<std::string>(), "sim3");
  EXPECT_EQ(j.at("poses_in_every_run").get<int>(), 50);
  EXPECT_NEAR(j.at("runs").at(1).at("scale_onto_fused").get<double>(), 1.0 / 3.0, 1e-9);
  EXPECT_LT(j.at("spread_max").get<double>(), 1e-6);
}

// Runs whose reports say metric (a stereo rig) are aligned rigidly: a run at another scale
// stays at that scale in the mean.
TEST_F(FuseCli, MetricRunsFuseRigidly) {
  WriteRunFolder(dir_ / "s0", truth_, "metric (stereo)");
  WriteRunFolder(dir_ / "s1", testing::Transformed(truth_, 1.02, {0.1, -0.3, 0.7}, {0, 0, 0}),
                 "metric (stereo)");
  const auto r = testing::RunDala(
      "fuse " + dir_ / "s0" + " " + dir_ / "s1" + " --out " + dir_ / "fused", dir_ / "log");
  ASSERT_EQ(r.status, 0) << r.log();
  EXPECT_THAT(r.out, HasSubstr("aligned by se3"));
  std::ifstream report(dir_ / "fused/fusion.json");
  const nlohmann::json j = nlohmann::json::parse(report);
  EXPECT_DOUBLE_EQ(j.at("runs").at(1).at("scale_onto_fused").get<double>(), 1.0);
  EXPECT_GT(j.at("spread_max").get<double>(), 0.01);  // 2 % of a 10 m helix, halved.
}

TEST_F(FuseCli, BadInputSaysWhatIsWrongAndWritesNothing) {
  WriteRunFolder(dir_ / "r0", truth_, "arbitrary (monocular)");
  std::filesystem::create_directories(dir_ / "empty");
  struct Case {
    std::string args, message;
  } cases[] = {
      {"fuse " + dir_ / "r0" + " --out " + dir_ / "fused", "expected at least 2 runs"},
      {"fuse " + dir_ / "r0" + " " + dir_ / "r0", "--out DIR is required"},
      {"fuse " + dir_ / "r0" + " " + dir_ / "missing" + " --out " + dir_ / "fused",
       "no such run folder or trajectory file"},
      {"fuse " + dir_ / "r0" + " " + dir_ / "empty" + " --out " + dir_ / "fused",
       "the folder has no trajectory.txt"},
      {"fuse " + dir_ / "r0" + " " + dir_ / "r0" + " --out " + dir_ / "fused" +
           " --fuse_align affine",
       "expected auto, sim3, se3 or none"},
  };
  for (const Case& c : cases) {
    const auto r = testing::RunDala(c.args, dir_ / "log");
    EXPECT_EQ(r.status, 2) << c.args;
    EXPECT_THAT(r.err, HasSubstr(c.message)) << c.args;
  }
  // Runs of other frames (an hour later): nothing to align on.
  WriteTrajectoryTum(dir_ / "later.txt", testing::HelixTrajectory(50, 3600000000000LL));
  const auto r = testing::RunDala(
      "fuse " + dir_ / "r0" + " " + dir_ / "later.txt" + " --out " + dir_ / "fused", dir_ / "log");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("are these runs of the same frames?"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "fused"));
}

}  // namespace
}  // namespace dala
