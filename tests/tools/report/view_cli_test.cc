// `dala run` writes report.html (and, with --video, the frames video); `dala view` writes it again
// from the run's folder, or from a saved map alone, and prints where; a folder that is no run is an
// error that says so.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ReadAll;

// `dala ARGS`: its exit code; what it printed is in dala.out and dala.err of DIR.
int Dala(const std::string& args, const testing::TempDir& dir) {
  return testing::RunDala(args, dir / "dala").status;
}

TEST(ViewCli, WritesTheReportOfARunAndOfASavedMap) {
  testing::TempDir dir;
  sim::SimOptions sim;
  sim.frames = 30;
  sim.width = 320;
  sim.height = 240;
  sim.seed = 5;
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  // Run from the folder with relative paths: `dala view` from elsewhere still finds the ground
  // truth (report.json's dataset.absolute_path).
  const int run_status =
      std::system(("cd " + dir.path() + " && " + DALA_BINARY +
                   " run seq --out run --progress=false --video run/frames.mp4 > " +
                   (dir / "dala.out") + " 2> " + (dir / "dala.err"))
                      .c_str());
  ASSERT_TRUE(WIFEXITED(run_status) && WEXITSTATUS(run_status) == 0) << ReadAll(dir / "dala.err");
  EXPECT_NE(ReadAll(dir / "dala.out").find("video       run/frames.mp4 (30 frames"),
            std::string::npos)
      << ReadAll(dir / "dala.out");
  EXPECT_NE(ReadAll(dir / "dala.out").find("report      run/report.html"), std::string::npos)
      << ReadAll(dir / "dala.out");
  const std::string html = dir / "run/report.html";
  const std::string from_run = ReadAll(html);
  ASSERT_NE(from_run.find("\"ground_truth\""), std::string::npos);
  std::filesystem::remove(html);

  // Again from the folder, given from another working directory: the ground truth is found
  // again (the dataset's absolute path).
  ASSERT_EQ(Dala("view " + (dir / "run"), dir), 0) << ReadAll(dir / "dala.err");
  EXPECT_EQ(ReadAll(dir / "dala.out"), html + "\n");
  const std::string from_view = ReadAll(html);
  EXPECT_NE(from_view.find("\"ground_truth\""), std::string::npos);
  EXPECT_NE(from_view.find("\"summary_text\":\"frames      30"), std::string::npos);

  // A saved map alone: beside it, not over the run's report.
  ASSERT_EQ(Dala("view " + (dir / "run/map.dmap"), dir), 0) << ReadAll(dir / "dala.err");
  EXPECT_EQ(ReadAll(dir / "dala.out"), (dir / "run/map_report.html") + "\n");
  EXPECT_NE(ReadAll(dir / "run/map_report.html").find("keyframes, "), std::string::npos);

  // Not a run: exit 2, naming what is missing.
  std::filesystem::create_directories(dir / "empty");
  EXPECT_EQ(Dala("view " + (dir / "empty"), dir), 2);
  EXPECT_NE(ReadAll(dir / "dala.err").find("report.json: missing"), std::string::npos)
      << ReadAll(dir / "dala.err");
}

}  // namespace
}  // namespace dala
