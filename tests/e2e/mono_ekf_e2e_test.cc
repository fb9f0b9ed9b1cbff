// End to end: the monocular EKF through dala::System on rendered sequences, one camera (the
// constant-velocity model started by the two-view initialisation) and with the dataset's
// odometry (System fills FrameMeasurement::odometry from Frame::T_w_odom).
#include <gtest/gtest.h>

#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "backend/ekf/mono_ekf.h"
#include "backend/system.h"
#include "core/eval/evaluate.h"
#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

// Bounds of the ATE / path length: 1.5x the best values recorded, one camera (Sim(3), 149 of
// 150 frames with a pose) and with odometry (SE(3)).
constexpr double kOneCameraRoverPercentBest = 3.45;
constexpr double kOdometryRoverPercentBest = 0.349;

struct MonoRun {
  Trajectory trajectory;
  EvalResult eval;
  std::vector<FrameStats> stats;
  std::string scale;
};

// frames_odometry: Frame::T_w_odom from the sequence's noisy odometry (as `dala synth
// --odometry` writes it), else none.
MonoRun RunMonoEkf(const sim::SyntheticSequence& seq, bool frames_odometry,
                   AlignmentType alignment) {
  SystemOptions options;
  options.estimator = "ekf";
  options.mode = "mono";
  System system(seq.rig(), options);
  const sim::SimOptions& so = seq.options();
  const Trajectory odometry =
      sim::NoisyOdometry(seq.ground_truth(), so.seed, so.odometry_sigma_rot,
                         so.odometry_sigma_trans, so.odometry_sigma_trans_fraction);
  for (size_t i = 0; i < seq.size(); ++i) {
    Frame frame = seq.Render(i);
    frame.right = cv::Mat();  // One camera.
    if (frames_odometry) frame.T_w_odom = odometry.poses[i].T_w_c;
    system.Track(frame);
  }
  MonoRun run;
  run.trajectory = system.trajectory();
  EvalOptions eval;
  eval.alignment = alignment;
  run.eval = Evaluate(seq.ground_truth(), run.trajectory, eval);
  run.stats = system.stats();
  run.scale = system.ScaleDescription();
  return run;
}

sim::SimOptions Preset(const std::string& name, int frames, uint32_t seed) {
  sim::SimOptions sim;
  sim.preset = name;
  sim.frames = frames;
  sim.seed = seed;
  return sim;
}

// One camera, no odometry: the constant-velocity filter starts from the two-view initialisation
// and follows a 150-frame stretch of the rover loop; Sim(3)-aligned ATE as a fraction of the path.
TEST(MonoEkfE2e, RoverStretchOneCameraConstantVelocity) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 150, 5));
  const MonoRun run = RunMonoEkf(seq, /*frames_odometry=*/false, AlignmentType::kSim3);
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_EQ(run.scale, "arbitrary (monocular)");
  int initialising = 0;
  for (const FrameStats& s : run.stats) initialising += s.status == TrackingStatus::kInitializing;
  const double fraction = run.eval.ate.translation.rmse / seq.PathLength();
  std::cout << "[ measured ] ekf/mono one camera, rover 150 frames: " << initialising
            << " frames initialising, " << run.trajectory.size() << " poses, path "
            << seq.PathLength() << " m, Sim(3) ATE " << run.eval.ate.translation.rmse << " m ("
            << 100 * fraction << " %)" << std::endl;
  EXPECT_GE(run.trajectory.size(), seq.size() - 20);
  testing::ExpectWithinBound("ekf/mono one camera, Sim(3) ATE / path, rover 150 frames",
                             100 * fraction, kOneCameraRoverPercentBest, "%");
}

// Pure rotation: the two-view initialisation never succeeds and every frame says why (the
// reason printed is the parallax: too little beyond a pure rotation); no frame gets a pose.
TEST(MonoEkfE2e, RotationNeverInitialisesAndSaysWhy) {
  const sim::SyntheticSequence seq(Preset("rotation", 60, 3));
  const MonoRun run = RunMonoEkf(seq, /*frames_odometry=*/false, AlignmentType::kSim3);
  EXPECT_TRUE(run.trajectory.empty() || run.trajectory.size() == 1u)
      << run.trajectory.size() << " poses";
  for (size_t i = 1; i < run.stats.size(); ++i) {
    const FrameStats& s = run.stats[i];
    EXPECT_EQ(s.status, TrackingStatus::kInitializing) << "frame " << i;
    EXPECT_FALSE(s.valid);
    EXPECT_EQ(s.note.rfind("initialising: ", 0), 0u) << s.note;
    EXPECT_GT(s.note.size(), std::string("initialising: ").size() + 10) << s.note;
  }
  std::cout << "[ measured ] rotation: last note '" << run.stats.back().note << "'" << std::endl;
}

// With the frames' odometry the System fills m.odometry: the filter predicts with it from the
// second frame, every frame has a pose, the scale is metric (SE(3) alignment) and said so.
TEST(MonoEkfE2e, OdometryIsReadIntoTheMeasurementAndFixesTheScale) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 100, 7));
  const MonoRun run = RunMonoEkf(seq, /*frames_odometry=*/true, AlignmentType::kSE3);
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_EQ(run.scale, "metric (odometry)");
  EXPECT_EQ(run.trajectory.size(), seq.size());
  for (size_t i = 1; i < run.stats.size(); ++i) EXPECT_TRUE(run.stats[i].valid) << "frame " << i;
  const double fraction = run.eval.ate.translation.rmse / seq.PathLength();
  std::cout << "[ measured ] ekf/mono with odometry, rover 100 frames: SE(3) ATE "
            << run.eval.ate.translation.rmse << " m (" << 100 * fraction << " %)" << std::endl;
  testing::ExpectWithinBound("ekf/mono with odometry, ATE / path, rover 100 frames",
                             100 * fraction, kOdometryRoverPercentBest, "%");
}

// `dala run` on dir/seq with FLAGS, its outputs in dir/NAME: all it printed (it must succeed).
std::string DalaRunLog(const testing::TempDir& dir, const std::string& flags,
                       const std::string& name) {
  const testing::DalaCliResult r = testing::RunDala(
      "run " + (dir / "seq") + " --out " + (dir / name) + " " + flags + " --progress=false",
      dir / name);
  EXPECT_EQ(r.status, 0) << flags << "\n" << r.log();
  return r.log();
}

// `dala run` on a folder written with --odometry: the reader gives the odometry, the System
// uses it, the summary says the scale is metric.
TEST(MonoEkfE2e, DalaRunUsesTheFolderOdometry) {
  testing::TempDir dir;
  sim::SyntheticDatasetOutputs outputs;
  outputs.odometry = true;
  sim::WriteSyntheticDataset(Preset("rover_loop", 20, 9), dir / "seq", outputs);
  const std::string log = DalaRunLog(dir, "--estimator ekf --mode mono", "out");
  EXPECT_NE(log.find("scale       metric (odometry)"), std::string::npos) << log;
  EXPECT_EQ(log.find("for one camera use --estimator ba"), std::string::npos) << log;
}

// `dala run --estimator ekf --mode mono` with one camera and no odometry: the summary says that
// this filter drifts in scale and points to the BA; the BA and stereo EKF runs do not say it.
TEST(MonoEkfE2e, DalaRunSaysWhereOneCameraDoesNotHold) {
  testing::TempDir dir;
  sim::WriteSyntheticDataset(Preset("rover_loop", 20, 9), dir / "seq", {});
  const std::string ekf_mono = DalaRunLog(dir, "--estimator ekf --mode mono", "ekf_mono");
  EXPECT_NE(ekf_mono.find("scale       arbitrary (monocular)"), std::string::npos) << ekf_mono;
  EXPECT_NE(ekf_mono.find("note        the mono EKF from one camera (no odometry) drifts in "
                          "scale"),
            std::string::npos)
      << ekf_mono;
  EXPECT_NE(ekf_mono.find("use --estimator ba"), std::string::npos) << ekf_mono;
  const std::vector<std::pair<std::string, std::string>> others = {
      {"--estimator ba --mode mono", "ba_mono"}, {"--estimator ekf", "ekf_stereo"}};
  for (const auto& [flags, name] : others) {
    const std::string other = DalaRunLog(dir, flags, name);
    EXPECT_EQ(other.find("for one camera use --estimator ba"), std::string::npos)
        << flags << "\n" << other;
  }
}

}  // namespace
}  // namespace dala
