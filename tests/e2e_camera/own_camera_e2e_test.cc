// End to end through a distorting lens: `dala synth --distortion / --fisheye` renderings read
// through their calibration files (undistorted, or rectified at open) give a mean ATE over
// three scenes within 1.5x of the same scenes rendered without a lens; and the calibration
// files written in every format read back to the same camera.
#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "backend/system.h"
#include "core/eval/evaluate.h"
#include "core/io/camera_calibration.h"
#include "core/io/dataset.h"
#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/test_util.h"

namespace dala {
namespace {

// ATE of the stereo BA over a dataset folder read as `dala run` reads it.
double RunAte(const std::string& folder, const DatasetOptions& dataset_options = {}) {
  std::unique_ptr<Dataset> dataset = OpenDataset(folder, dataset_options);
  System system(dataset->rig(), SystemOptions());
  Frame frame;
  while (dataset->Next(&frame)) system.Track(frame);
  const EvalResult eval = Evaluate(*dataset->ground_truth(), system.trajectory(), EvalOptions());
  EXPECT_TRUE(eval.ok) << folder << ": " << eval.error;
  return eval.ate.translation.rmse;
}

sim::SimOptions Rendering(const std::string& lens, uint64_t seed = 5) {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 40;
  sim.seed = seed;
  sim.lens = lens;
  return sim;
}

// One rendering is one draw: through a lens the detector sees other pixels, and over ten scenes
// (seeds 1-10) the radtan / pinhole ATE ratio of a single scene spans 0.7-2.0 while the means
// differ by 4 % (docs/results.md). So the mean over three scenes is compared, with 1.5x: a lens
// read as a pinhole (the distortion ignored) gives ~10x (0.05-0.08 m against 0.005 m).
TEST(OwnCameraE2e, DistortedRenderingsWithinOnePointFiveTimesTheUndistortedAte) {
  testing::TempDir dir;
  const std::vector<uint64_t> scenes = {5, 6, 7};
  std::map<std::string, double> mean_ate;
  for (const std::string lens : {"pinhole", "radtan", "fisheye"}) {
    for (const uint64_t seed : scenes) {
      const std::string folder = dir / (lens + std::to_string(seed));
      sim::WriteSyntheticDataset(Rendering(lens, seed), folder, false);
      // Read by default through calibration/kalibr.yaml; the OpenCV file gives the same rig.
      mean_ate[lens] += RunAte(folder) / scenes.size();
      if (lens == "pinhole" || seed != scenes.front()) continue;
      DatasetOptions opencv;
      opencv.calibration_yaml = folder + "/calibration/opencv.yml";
      const auto by_opencv = OpenDataset(folder, opencv);
      const auto by_kalibr = OpenDataset(folder);
      EXPECT_NEAR(by_opencv->rig().left.fx, by_kalibr->rig().left.fx, 1e-6);
      EXPECT_NEAR(by_opencv->rig().baseline, by_kalibr->rig().baseline, 1e-9);
    }
  }
  for (const std::string lens : {"radtan", "fisheye"}) {
    std::cout << "[ measured ] stereo BA, rover_loop 40 frames, mean over seeds 5-7: ATE " << lens
              << " " << mean_ate[lens] << " m, pinhole " << mean_ate["pinhole"] << " m, ratio "
              << mean_ate[lens] / mean_ate["pinhole"] << std::endl;
    EXPECT_LT(mean_ate[lens], 1.5 * mean_ate["pinhole"]) << lens;
  }
}

TEST(OwnCameraE2e, SynthCalibrationFilesReadBackInEveryFormat) {
  testing::TempDir dir;
  sim::SimOptions sim = Rendering("radtan");
  sim.frames = 1;
  sim.stereo = false;
  sim.width = 160;
  sim.height = 120;
  sim.fx = sim.fy = 100;
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  for (const char* file : {"opencv.yml", "kalibr.yaml", "ros_camera_info.yaml", "dala.yaml"}) {
    const CameraCalibration c = ReadCameraCalibration(dir / (std::string("seq/calibration/") + file));
    EXPECT_EQ(c.cam0.width, 160) << file;
    EXPECT_DOUBLE_EQ(c.cam0.fx, 100) << file;
    EXPECT_DOUBLE_EQ(c.cam0.distortion[0], -0.28) << file;
    EXPECT_EQ(c.cam0.model, LensModel::kRadtan) << file;
  }
}

}  // namespace
}  // namespace dala
