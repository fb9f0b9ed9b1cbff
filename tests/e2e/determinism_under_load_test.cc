// `dala run` twice on the same rendered loop while busy processes load every core: the outputs
// are byte-identical. The solvers stop on iteration limits only, never on the wall clock
// (backend/ba/solver_time.h), so a loaded machine cannot change a result (DESIGN.md).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ReadAll;

// Child processes that spin until the object dies.
class BusyLoad {
 public:
  explicit BusyLoad(int processes) {
    for (int i = 0; i < processes; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        volatile unsigned long spin = 0;
        for (;;) spin = spin + 1;
      }
      if (pid > 0) pids_.push_back(pid);
    }
  }
  ~BusyLoad() {
    for (const pid_t pid : pids_) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
  }
  size_t size() const { return pids_.size(); }

 private:
  std::vector<pid_t> pids_;
};

// report.json without what measures time (per-frame "ms", fps and the ms tables, the printed
// summary).
nlohmann::json WithoutTimings(nlohmann::json report) {
  for (nlohmann::json& frame : report.at("frames")) {
    frame.erase("ms");
    frame.erase("rss_mb");  // Memory, like time, depends on the machine, not on the input.
  }
  nlohmann::json& summary = report.at("summary");
  for (const char* key : {"fps", "ms_mean", "ms_median", "ms_p95", "ms_max", "stages_ms",
                          "loop_ms_per_keyframe", "peak_rss_mb"}) {
    EXPECT_TRUE(summary.contains(key)) << key;
    summary.erase(key);
  }
  summary.at("refinement").erase("time_s");  // The global BA's wall time (ba.final_ba).
  // The summary as printed: its time, fps and memory lines, and the output folder.
  EXPECT_TRUE(report.contains("summary_text"));
  report.erase("summary_text");
  return report;
}

// `dala run DATASET EXTRA` twice while busy processes load every core; the outputs (minus
// timings) are byte-identical. Returns the first run's report.
nlohmann::json ExpectIdenticalRunsUnderLoad(const testing::TempDir& dir, const std::string& dataset,
                                            const std::string& extra,
                                            const std::vector<std::string>& more_files = {}) {
  const BusyLoad load(static_cast<int>(std::max(2u, std::thread::hardware_concurrency())));
  EXPECT_GE(load.size(), 2u);
  for (const char* out : {"a", "b"}) {
    const testing::DalaCliResult r = testing::RunDala(
        "run " + dataset + " " + extra + " --out " + (dir / out) + " --progress=false", dir / out);
    EXPECT_EQ(r.status, 0) << r.log();
  }
  std::vector<std::string> files = {"trajectory.txt", "trajectory_kitti.txt", "map.ply",
                                    "map.dmap"};
  files.insert(files.end(), more_files.begin(), more_files.end());
  for (const std::string& file : files) {
    const std::string a = ReadAll(dir / ("a/" + file));
    EXPECT_FALSE(a.empty()) << file;
    EXPECT_TRUE(a == ReadAll(dir / ("b/" + file))) << file << " differs";
  }
  const nlohmann::json a = nlohmann::json::parse(ReadAll(dir / "a/report.json"));
  const nlohmann::json b = nlohmann::json::parse(ReadAll(dir / "b/report.json"));
  EXPECT_EQ(WithoutTimings(a), WithoutTimings(b));
  return a;
}

TEST(DeterminismUnderLoad, TwoRunsGiveIdenticalFiles) {
  testing::TempDir dir;
  // The small loop (125 m) at 3 Hz, small images: ~3 s a run unloaded, and it closes loops, so
  // the window BA, the pose-only tracking and the pose graph all solve under load.
  sim::SimOptions sim;
  sim.preset = "small_loop";
  sim.fps = 3;
  sim.width = 320;
  sim.height = 240;
  sim.fx = sim.fy = 200;
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  // With the global BA after the run (ba.final_ba), which solves under load too.
  const nlohmann::json a =
      ExpectIdenticalRunsUnderLoad(dir, dir / "seq", "--set ba.final_ba=always");
  EXPECT_GE(a.at("summary").at("loops_closed").get<int>(), 1) << "the pose graph did not run";
  EXPECT_TRUE(a.at("summary").at("refinement").at("done").get<bool>());
}

// The real KITTI 06 frames with configs/kitti.yaml (the window also estimates the rig's
// disparity offset), stereo and one camera.
TEST(DeterminismUnderLoad, KittiRunsGiveIdenticalFiles) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  const std::string kitti = testing::SharedDataDir() + "/kitti06_0000-0050";
  {
    testing::TempDir dir;
    ExpectIdenticalRunsUnderLoad(dir, kitti,
                                 std::string("--config ") + DALA_SOURCE_DIR + "/configs/kitti.yaml");
  }
  testing::TempDir dir;
  ExpectIdenticalRunsUnderLoad(dir, kitti, "--mode mono");
}

// Three draws of one camera stepped on two threads (`dala run --draws 3`): the fused trajectory
// and every draw's are the same run after run, whichever thread finished first.
TEST(DeterminismUnderLoad, DrawsOnThreadsGiveIdenticalFiles) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  testing::TempDir dir;
  const nlohmann::json a = ExpectIdenticalRunsUnderLoad(
      dir, testing::SharedDataDir() + "/kitti06_0000-0050", "--mode mono --draws 3 --threads 2",
      {"draws/seed_0.txt", "draws/seed_1.txt", "draws/seed_2.txt"});
  EXPECT_EQ(a.at("summary").at("draws").at("fused").get<int>(), 3);
}

}  // namespace
}  // namespace dala
