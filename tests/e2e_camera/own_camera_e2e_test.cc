// End to end through a distorting lens: `dala synth --distortion / --fisheye` renderings read
// through their calibration files (undistorted, or rectified at open) give an ATE within 1.2x
// of the same sequence rendered without a lens; and the calibration files written in every
// format read back to the same camera.
#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <string>

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

sim::SimOptions Rendering(const std::string& lens) {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 40;
  sim.seed = 5;
  sim.lens = lens;
  return sim;
}

TEST(OwnCameraE2e, DistortedRenderingsWithinOnePointTwoTimesTheUndistortedAte) {
  testing::TempDir dir;
  sim::WriteSyntheticDataset(Rendering("pinhole"), dir / "pinhole", false);
  const double ate_pinhole = RunAte(dir / "pinhole");
  for (const std::string lens : {"radtan", "fisheye"}) {
    sim::WriteSyntheticDataset(Rendering(lens), dir / lens, false);
    // Read by default through calibration/kalibr.yaml; the OpenCV file gives the same rig.
    const double ate = RunAte(dir / lens);
    DatasetOptions opencv;
    opencv.calibration_yaml = dir / (lens + "/calibration/opencv.yml");
    const auto by_opencv = OpenDataset(dir / lens, opencv);
    const auto by_kalibr = OpenDataset(dir / lens);
    EXPECT_NEAR(by_opencv->rig().left.fx, by_kalibr->rig().left.fx, 1e-6);
    EXPECT_NEAR(by_opencv->rig().baseline, by_kalibr->rig().baseline, 1e-9);
    std::cout << "[ measured ] stereo BA, rover_loop 40 frames: ATE " << lens << " " << ate
              << " m, pinhole " << ate_pinhole << " m, ratio " << ate / ate_pinhole << std::endl;
    EXPECT_LT(ate, 1.2 * ate_pinhole) << lens;
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
