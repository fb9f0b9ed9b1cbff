// `dala eval` end to end: the binary (DALA_BINARY) on generated files.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/trajectory_io.h"
#include "tests/core/eval/eval_test_util.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;

struct CliResult {
  int status = -1;
  std::string out;  // stdout only
  std::string err;  // stderr only
};

// Runs `dala ARGS`, capturing stdout and stderr separately.
CliResult RunDala(const std::string& args, const testing::TempDir& dir) {
  const std::string err_path = dir / "stderr.txt";
  const std::string cmd = std::string(DALA_BINARY) + " " + args + " 2>" + err_path;
  CliResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof(buf), pipe)) > 0) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream is(err_path);
  r.err.assign(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
  return r;
}

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    gt_ = testing::HelixTrajectory(200);
    est_ = gt_;
    for (size_t i = 0; i < est_.size(); ++i) {
      est_.poses[i].T_w_c.translation() += Eigen::Vector3d(0.5, 0.0, 0.02 * (i % 3));
    }
    WriteTrajectoryTum(dir_ / "gt.txt", gt_);
    WriteTrajectoryTum(dir_ / "est.txt", est_);
  }
  testing::TempDir dir_;
  Trajectory gt_, est_;
};

TEST_F(EvalCli, PrintsATable) {
  const CliResult r = RunDala("eval " + dir_ / "gt.txt" + " " + dir_ / "est.txt", dir_);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("pairs                  200"));
  EXPECT_THAT(r.out, HasSubstr("ATE (translation)"));
  EXPECT_THAT(r.out, HasSubstr("RPE (delta 1 frames, 199 pairs)"));
  EXPECT_THAT(r.out, HasSubstr("alignment              se3"));
}

TEST_F(EvalCli, JsonIsOneObjectWithTheKeys) {
  const CliResult r = RunDala("eval " + dir_ / "gt.txt" + " " + dir_ / "est.txt" +
                                  " --json --align none --delta-unit m --delta 2",
                              dir_);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);  // Throws if anything else is printed.
  EXPECT_EQ(j.at("pairs").get<int>(), 200);
  EXPECT_EQ(j.at("alignment").get<std::string>(), "none");
  EXPECT_EQ(j.at("rpe").at("unit").get<std::string>(), "metres");  // Dashed flag name works.
  EXPECT_DOUBLE_EQ(j.at("rpe").at("delta").get<double>(), 2.0);
  // No alignment: every error is at least the 0.5 m offset.
  EXPECT_GE(j.at("ate").at("min").get<double>(), 0.5 - 1e-6);
  for (const char* key : {"rmse", "mean", "median", "max"}) EXPECT_TRUE(j.at("ate").contains(key));
  EXPECT_TRUE(j.at("rpe").contains("rot_rmse_deg"));
  EXPECT_TRUE(j.contains("scale"));
}

TEST_F(EvalCli, PlotWritesAPng) {
  const std::string png = dir_ / "eval.png";
  const CliResult r =
      RunDala("eval " + dir_ / "gt.txt" + " " + dir_ / "est.txt" + " --plot " + png, dir_);
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_TRUE(std::filesystem::exists(png));
  std::ifstream is(png, std::ios::binary);
  char magic[4] = {};
  is.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
}

TEST_F(EvalCli, KittiFilesPairByIndexOrThroughTimes) {
  WriteTrajectoryKitti(dir_ / "gt_kitti.txt", gt_);
  WriteTrajectoryKitti(dir_ / "est_kitti.txt", est_);
  const CliResult ok =
      RunDala("eval " + dir_ / "gt_kitti.txt" + " " + dir_ / "est_kitti.txt" + " --json", dir_);
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_EQ(nlohmann::json::parse(ok.out).at("paired_by").get<std::string>(), "index");
  // Lengths differ: a clear error naming both sizes and --times.
  Trajectory shorter = est_;
  shorter.poses.resize(150);
  WriteTrajectoryKitti(dir_ / "short_kitti.txt", shorter);
  const CliResult bad =
      RunDala("eval " + dir_ / "gt_kitti.txt" + " " + dir_ / "short_kitti.txt", dir_);
  EXPECT_EQ(bad.status, 2);
  EXPECT_THAT(bad.err, HasSubstr("short_kitti.txt"));
  EXPECT_THAT(bad.err, HasSubstr("200 poses"));
  EXPECT_THAT(bad.err, HasSubstr("--times"));
  // A times file gives the short KITTI estimate stamps: it then associates with the TUM gt.
  {
    std::ofstream times(dir_ / "times.txt");
    times.precision(9);
    for (size_t i = 0; i < shorter.size(); ++i) {
      times << std::fixed << SecondsFromNs(shorter.poses[i].t_ns) << "\n";
    }
  }
  const CliResult timed = RunDala("eval " + dir_ / "gt.txt" + " " + dir_ / "short_kitti.txt" +
                                      " --times " + dir_ / "times.txt" + " --json",
                                  dir_);
  ASSERT_EQ(timed.status, 0) << timed.err;
  const nlohmann::json j = nlohmann::json::parse(timed.out);
  EXPECT_EQ(j.at("pairs").get<int>(), 150);
  EXPECT_EQ(j.at("paired_by").get<std::string>(), "time");
}

TEST_F(EvalCli, ErrorsExitWithStatus2AndNameTheProblem) {
  const CliResult missing = RunDala("eval " + dir_ / "nope.txt" + " " + dir_ / "est.txt", dir_);
  EXPECT_EQ(missing.status, 2);
  EXPECT_THAT(missing.err, HasSubstr("nope.txt"));
  // Stamps 1000 s apart: no pair; the message gives max diff and both time ranges.
  Trajectory late = testing::HelixTrajectory(20, 1000000000000LL);
  WriteTrajectoryTum(dir_ / "late.txt", late);
  const CliResult none =
      RunDala("eval " + dir_ / "gt.txt" + " " + dir_ / "late.txt" + " --max_diff 0.05", dir_);
  EXPECT_EQ(none.status, 2);
  EXPECT_THAT(none.err, HasSubstr("max diff 0.05"));
  EXPECT_THAT(none.err, HasSubstr("[1000.000000, 1001.900000] s"));
  EXPECT_THAT(none.err, HasSubstr("late.txt"));
  const CliResult bad_align =
      RunDala("eval " + dir_ / "gt.txt" + " " + dir_ / "est.txt" + " --align affine", dir_);
  EXPECT_EQ(bad_align.status, 2);
  EXPECT_THAT(bad_align.err, HasSubstr("--align=affine"));
  const CliResult one_arg = RunDala("eval " + dir_ / "gt.txt", dir_);
  EXPECT_EQ(one_arg.status, 2);
  const CliResult help = RunDala("eval --help", dir_);
  EXPECT_EQ(help.status, 0);
  EXPECT_THAT(help.out, HasSubstr("--max_diff"));
}

}  // namespace
}  // namespace dala
