// `dala run --draws N` (the binary): the draws' fused trajectory is written and evaluated, each
// draw's trajectory beside it (the first one is the run without --draws, byte for byte), and a
// wrong count exits 2 with a message and writes nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/trajectory_io.h"
#include "core/sim/dataset_writer.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;
using testing::ReadAll;
using testing::TempDir;

// The rendered sequence is written once for the suite (rendering takes longer than a run).
class RunDrawsCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new TempDir;
    sim::SimOptions sim;
    sim.preset = "rover_loop";
    sim.frames = 50;
    sim.seed = 3;
    sim::WriteSyntheticDataset(sim, *data_ / "seq", false);
  }
  static void TearDownTestSuite() {
    delete data_;
    data_ = nullptr;
  }
  testing::DalaCliResult Run(const std::string& args, const std::string& name) {
    return testing::RunDala(
        "run " + *data_ / "seq" + " --mode mono --progress=false " + args + " --out " + dir_ / name,
        dir_ / (name + "_log"));
  }
  static TempDir* data_;
  TempDir dir_;
};
TempDir* RunDrawsCli::data_ = nullptr;

TEST_F(RunDrawsCli, ThreeDrawsFusedAndEachWritten) {
  const auto plain = Run("", "plain");
  ASSERT_EQ(plain.status, 0) << plain.log();
  // A draw of an earlier run into the same folder, which this run does not have.
  std::filesystem::create_directories(dir_ / "draws/draws");
  std::ofstream(dir_ / "draws/draws/seed_7.txt") << "0 0 0 0 0 0 0 1\n";
  const auto r = Run("--draws 3 --threads 2", "draws");
  ASSERT_EQ(r.status, 0) << r.log();
  EXPECT_FALSE(std::filesystem::exists(dir_ / "draws/draws/seed_7.txt"));
  EXPECT_THAT(r.err, HasSubstr("3 draws (ransac_order_seed 0-2) on 2 threads"));
  EXPECT_THAT(r.out, HasSubstr("draws       3 runs (ransac_order_seed 0-2); 3 fused by sim3 into "
                               "the world of seed 0"));
  EXPECT_THAT(r.out, HasSubstr("the 3 draws fused)"));

  // Draw 0 is the run without --draws.
  EXPECT_EQ(ReadAll(dir_ / "draws/draws/seed_0.txt"), ReadAll(dir_ / "plain/trajectory.txt"));
  EXPECT_EQ(ReadAll(dir_ / "draws/map.dmap"), ReadAll(dir_ / "plain/map.dmap"));
  const nlohmann::json report = nlohmann::json::parse(ReadAll(dir_ / "draws/report.json"));
  const nlohmann::json& summary = report.at("summary");
  const nlohmann::json& draws = summary.at("draws");
  EXPECT_EQ(draws.at("count").get<int>(), 3);
  EXPECT_EQ(draws.at("fused").get<int>(), 3);
  EXPECT_EQ(draws.at("alignment").get<std::string>(), "sim3");
  ASSERT_EQ(draws.at("per_draw").size(), 3u);
  double worst = 0.0;
  for (int k = 0; k < 3; ++k) {
    const nlohmann::json& d = draws.at("per_draw").at(k);
    EXPECT_EQ(d.at("seed").get<int>(), k);
    const Trajectory t = ReadTrajectory(dir_ / ("draws/draws/seed_" + std::to_string(k) + ".txt"));
    EXPECT_EQ(d.at("frames_with_pose").get<size_t>(), t.size());
    worst = std::max(worst, d.at("ate_rmse").get<double>());
  }
  const double plain_ate = nlohmann::json::parse(ReadAll(dir_ / "plain/report.json"))
                               .at("summary")
                               .at("ate")
                               .at("rmse")
                               .get<double>();
  EXPECT_DOUBLE_EQ(draws.at("per_draw").at(0).at("ate_rmse").get<double>(), plain_ate);
  // trajectory.txt is the fusion: every frame a draw posed, and no worse than the worst draw.
  const Trajectory fused = ReadTrajectory(dir_ / "draws/trajectory.txt");
  EXPECT_EQ(summary.at("frames_with_pose").get<size_t>(), fused.size());
  EXPECT_GE(fused.size(), ReadTrajectory(dir_ / "plain/trajectory.txt").size());
  EXPECT_LE(summary.at("ate").at("rmse").get<double>(), worst);
  EXPECT_GT(draws.at("spread_max").get<double>(), 0.0);
  // Per frame: the draws' spread where the fusion has a pose, and the time of every draw.
  size_t with_spread = 0;
  for (const nlohmann::json& frame : report.at("frames")) {
    EXPECT_TRUE(frame.at("ms").contains("all_draws"));
    if (!frame.at("draws_spread").is_null()) ++with_spread;
  }
  EXPECT_EQ(with_spread, fused.size());
}

// Two frames: no draw of one camera has started a map. The run says the draws were not fused,
// writes its files (an empty trajectory, each draw's) and exits 0.
TEST_F(RunDrawsCli, DrawsWithoutATrajectoryAreNotFusedAndSaySo) {
  const auto r = Run("--draws 2 --max_frames 2", "short");
  ASSERT_EQ(r.status, 0) << r.log();
  EXPECT_THAT(r.out, HasSubstr("not fused: fewer than two draws have a trajectory; the "
                               "trajectory is seed 0's"));
  const nlohmann::json draws =
      nlohmann::json::parse(ReadAll(dir_ / "short/report.json")).at("summary").at("draws");
  EXPECT_EQ(draws.at("fused").get<int>(), 0);
  EXPECT_TRUE(draws.at("spread_median").is_null());
  for (const nlohmann::json& d : draws.at("per_draw")) EXPECT_FALSE(d.at("in_fusion").get<bool>());
  EXPECT_TRUE(std::filesystem::exists(dir_ / "short/trajectory.txt"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "short/draws/seed_1.txt"));
}

TEST_F(RunDrawsCli, AWrongCountSaysSoAndWritesNothing) {
  for (const char* args : {"--draws 0", "--draws -2", "--draws 2 --threads -1"}) {
    const auto r = Run(args, "bad");
    EXPECT_EQ(r.status, 2) << args << "\n" << r.log();
    EXPECT_THAT(r.err, HasSubstr(std::string(args).find("threads") != std::string::npos
                                     ? "--threads -1: give 0 (one per core) or more"
                                     : "give 1 (one run, the default) or more"))
        << args;
    EXPECT_FALSE(std::filesystem::exists(dir_ / "bad")) << args;
  }
}

}  // namespace
}  // namespace dala
