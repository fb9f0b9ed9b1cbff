// `dala run` (the binary) on a user's own camera: an image folder with a calibration file, times
// and ground truth runs and is evaluated; bad input (a video that cannot be opened, a calibration
// of another image size, an unknown lens, a bag without images) exits 2 with a message naming the
// file and the fix, and writes nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/io/bag_dataset.h"
#include "core/sim/dataset_writer.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::ReadAll;
using testing::TempDir;

// `dala run ARGS`: its exit code and stderr.
testing::DalaCliResult DalaRun(const std::string& args, const TempDir& dir) {
  return testing::RunDala("run " + args + " --progress=false", dir / "dala");
}

void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(RunOwnCameraCli, ImageFolderWithCalibrationTimesAndGroundTruth) {
  TempDir dir;
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 20;
  sim.stereo = false;
  sim.lens = "radtan";
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  const std::string seq = dir / "seq";
  const auto cli = DalaRun(seq + "/image_0 --calibration " + seq + "/calibration/opencv.yml --times " +
                          seq + "/times.txt --ground_truth " + seq + "/poses.txt --mode mono " +
                          "--out " + (dir / "out"),
                      dir);
  ASSERT_EQ(cli.status, 0) << cli.err;
  std::ifstream in(dir / "out/report.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["dataset"]["format"], "images");
  EXPECT_EQ(report["summary"]["frames"].get<int>(), 20);
  EXPECT_TRUE(report["summary"].contains("ate"));
}

TEST(RunOwnCameraCli, BadInputExitsTwoNamingTheFileAndWritesNothing) {
  TempDir dir;
  Write(dir / "cam.yaml", "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 64\nheight: 48\n");
  Write(dir / "broken.mp4", "not a video at all, only text");
  auto cli = DalaRun((dir / "broken.mp4") + " --calibration " + (dir / "cam.yaml") + " --mode mono " +
                    "--out " + (dir / "out"),
                dir);
  EXPECT_EQ(cli.status, 2);
  EXPECT_THAT(cli.err, HasSubstr("broken.mp4"));
  EXPECT_THAT(cli.err, HasSubstr("the file is the problem"));
  EXPECT_FALSE(fs::exists(dir / "out"));

  // A calibration of another image size than the images.
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 2;
  sim.stereo = false;
  sim.width = 96;
  sim.height = 64;
  sim.fx = sim.fy = 60;
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  cli = DalaRun((dir / "seq/image_0") + " --calibration " + (dir / "cam.yaml") +
                " --fps 10 --mode mono --out " + (dir / "out"),
            dir);
  EXPECT_EQ(cli.status, 2);
  EXPECT_THAT(cli.err, HasSubstr("is 96x64, expected 64x48 (from the calibration"));
  EXPECT_FALSE(fs::exists(dir / "out"));

  // An unknown distortion model.
  Write(dir / "ros.yaml",
        "image_width: 96\nimage_height: 64\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [60, 0, "
        "48, 0, 60, 32, 0, 0, 1]\ndistortion_model: rational_polynomial\ndistortion_coefficients:"
        "\n  rows: 1\n  cols: 8\n  data: [0.1, 0, 0, 0, 0, 0.2, 0, 0]\n");
  cli = DalaRun((dir / "seq/image_0") + " --calibration " + (dir / "ros.yaml") +
                " --fps 10 --mode mono --out " + (dir / "out"),
            dir);
  EXPECT_EQ(cli.status, 2);
  EXPECT_THAT(cli.err, HasSubstr("ros.yaml: distortion_model: unknown distortion model"));
  EXPECT_FALSE(fs::exists(dir / "out"));

  // A bag: without images (or, in a build without bags, what to install).
  Write(dir / "empty.bag", "");
  cli = DalaRun((dir / "empty.bag") + " --mode mono --out " + (dir / "out"), dir);
  EXPECT_EQ(cli.status, 2);
  EXPECT_THAT(cli.err, HasSubstr("empty.bag"));
  if (!HaveBagSupport()) {
    EXPECT_THAT(cli.err, HasSubstr("install librosbag-dev"));
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace dala
