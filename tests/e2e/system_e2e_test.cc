// End to end: dala::System (frontend + sliding-window BA) on rendered stereo sequences with exact
// ground truth, and `dala run` on a rendered dataset folder.
#include <gtest/gtest.h>

#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "backend/system.h"
#include "core/error.h"
#include "core/eval/evaluate.h"
#include "core/io/trajectory_io.h"
#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

struct SystemRun {
  Trajectory trajectory;
  EvalResult eval;
  int lost = 0;
  std::optional<double> disparity_offset_px;  // in use after the last frame.
  // With `finish`: after System::Finish (the global BA of ba.final_ba, when it runs).
  std::optional<EvalResult> finished_eval;
  std::optional<double> finished_offset_px;
  bool refined = false;  // Finish ran the global BA.
};

SystemRun RunSystem(const sim::SyntheticSequence& seq, const SystemOptions& options,
                    bool finish = false) {
  System system(seq.rig(), options);
  SystemRun run;
  for (size_t i = 0; i < seq.size(); ++i) {
    run.lost += system.Track(seq.Render(i)).status == TrackingStatus::kLost;
  }
  run.trajectory = system.trajectory();
  run.eval = Evaluate(seq.ground_truth(), run.trajectory, EvalOptions());
  if (!system.stats().empty()) run.disparity_offset_px = system.stats().back().disparity_offset_px;
  if (finish) {
    run.refined = system.Finish().done;
    run.finished_eval = Evaluate(seq.ground_truth(), system.trajectory(), EvalOptions());
    run.finished_offset_px = system.estimator().DisparityOffsetPx();
  }
  return run;
}

// The first `frames` frames of the rendered preset, rendered with `seed`.
sim::SimOptions PresetStretch(const std::string& preset, int frames, uint32_t seed) {
  sim::SimOptions sim;
  sim.preset = preset;
  sim.frames = frames;
  sim.seed = seed;
  return sim;
}

sim::SimOptions RoverStretch(int frames, uint32_t seed) {
  return PresetStretch("rover_loop", frames, seed);
}

// A 150-frame stretch of the rover loop (~28 m): every frame gets a pose, and the ATE is a
// small fraction of the path (bound: docs/reliability.md).
TEST(SystemE2e, RoverStretchStereoBa) {
  const sim::SyntheticSequence seq(RoverStretch(150, 5));
  const SystemRun run = RunSystem(seq, SystemOptions());
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_EQ(run.trajectory.size(), seq.size());
  EXPECT_EQ(run.lost, 0);
  const double fraction = run.eval.ate.translation.rmse / seq.PathLength();
  std::cout << "[ measured ] rover 150 frames, path " << seq.PathLength() << " m, ATE "
            << run.eval.ate.translation.rmse << " m (" << 100 * fraction << " %)" << std::endl;
  testing::ExpectWithinBound("ba/stereo ATE / path, rover 150 frames", 100 * fraction, 0.0586,
                             "%");
}

// A still camera (the rover's first view, 300 frames that differ by their image noise only):
// the keyframe policy adds none after the first (the frame-count criterion waits for motion:
// otherwise a keyframe every 10 frames, ~0.5 MB each, without end), every frame is tracked, and
// the pose stays where it is.
TEST(SystemE2e, StillCameraKeepsItsKeyframe) {
  const sim::SyntheticSequence seq(RoverStretch(1, 5));
  const Pose T_w_c = seq.T_w_c0(0);
  const cv::Mat left = seq.RenderView(T_w_c);
  const cv::Mat right = seq.RenderView(T_w_c * seq.T_c0_c1());
  System system(seq.rig(), SystemOptions());
  int keyframes = 0, lost = 0;
  cv::RNG rng(7);
  for (int i = 0; i < 300; ++i) {
    Frame f;
    f.id = FrameId(i);
    f.t_ns = 100'000'000LL * i;
    cv::Mat noise(left.size(), CV_16S);
    for (const cv::Mat* clean : {&left, &right}) {
      rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
      cv::Mat noisy;
      cv::add(*clean, noise, noisy, cv::noArray(), CV_8U);
      (clean == &left ? f.left : f.right) = noisy;
    }
    const TrackResult r = system.Track(f);
    keyframes += r.keyframe;
    lost += !r.valid;
  }
  double largest = 0.0;
  for (const StampedPose& p : system.trajectory().poses) {
    largest = std::max(largest, p.T_w_c.translation().norm());
  }
  std::cout << "[ measured ] still camera, 300 frames: " << keyframes
            << " keyframes, largest position " << largest << " m" << std::endl;
  EXPECT_EQ(keyframes, 1);
  EXPECT_EQ(lost, 0);
  testing::ExpectWithinBound("still camera 300 frames, largest position", largest, 0.00335, "m");
}

// The window solve in the background (default) and in the caller's thread give the same
// trajectory, bit for bit: the overlap with the next frame's frontend must not change results.
TEST(SystemE2e, BackgroundWindowSolveGivesTheSameTrajectory) {
  const sim::SyntheticSequence seq(RoverStretch(60, 5));
  SystemOptions foreground;
  foreground.ba.background_solve = false;
  SystemOptions background;
  ASSERT_TRUE(background.ba.background_solve);
  const SystemRun a = RunSystem(seq, foreground);
  const SystemRun b = RunSystem(seq, background);
  ASSERT_EQ(a.trajectory.size(), seq.size());
  ASSERT_EQ(b.trajectory.size(), seq.size());
  for (size_t i = 0; i < seq.size(); ++i) {
    EXPECT_EQ(a.trajectory.poses[i].T_w_c.matrix(), b.trajectory.poses[i].T_w_c.matrix())
        << "frame " << i;
  }
}

// The guided local-map search turns itself on in stereo where the frame-to-frame tracks break
// (LocalMapSearchOptions::stereo_when_tracked_below): the rendered `fast` preset (11 m/s, heading
// wobbles) keeps ~43 % of its points from one frame to the next and gets it; the slow rover
// keeps ~72 % and does not, so its trajectory is bit for bit the one without the option.
// Measured (150 frames each) with the window at 1 px: fast ATE 0.0232 m with it, 0.0435 m
// without; bound: at most 0.7x. The window is held at 1 px here because at the stereo default
// (0.5 px) this rendered run no longer shows the search's gain (0.0363 m with it, 0.0326 m
// without), while real fast drives do: KITTI 06 kept at every 2nd / 3rd frame is 1.49x / 1.16x
// worse without it at 0.5 px (docs/results.md, "a stereo rig's window at 0.5 px").
TEST(SystemE2e, GuidedSearchTurnsOnWhereTracksBreak) {
  const sim::SyntheticSequence fast_seq(PresetStretch("fast", 150, 1));
  const sim::SyntheticSequence rover_seq(RoverStretch(150, 5));
  SystemOptions automatic;
  automatic.ba.observation_sigma_px = 1.0;
  SystemOptions never = automatic;
  never.frontend.local_map.stereo_when_tracked_below = 0;
  const SystemRun fast_auto = RunSystem(fast_seq, automatic);
  const SystemRun fast_never = RunSystem(fast_seq, never);
  ASSERT_TRUE(fast_auto.eval.ok && fast_never.eval.ok);
  std::cout << "[ measured ] fast 150 frames: ATE " << fast_auto.eval.ate.translation.rmse
            << " m with the search turning on, " << fast_never.eval.ate.translation.rmse
            << " m without" << std::endl;
  EXPECT_LT(fast_auto.eval.ate.translation.rmse, 0.7 * fast_never.eval.ate.translation.rmse);
  EXPECT_EQ(fast_auto.trajectory.size(), fast_seq.size());

  const SystemRun rover_auto = RunSystem(rover_seq, automatic);
  const SystemRun rover_never = RunSystem(rover_seq, never);
  ASSERT_EQ(rover_auto.trajectory.size(), rover_never.trajectory.size());
  for (size_t i = 0; i < rover_auto.trajectory.size(); ++i) {
    ASSERT_EQ(rover_auto.trajectory.poses[i].T_w_c.matrix(),
              rover_never.trajectory.poses[i].T_w_c.matrix())
        << "frame " << i << ": the search ran on the slow rover";
  }
}

// A rig whose rectification leaves every disparity 0.3 px too small (as KITTI 06's: the right
// image rendered with its principal point 0.3 px off calib.txt's): by default the BA calibrates
// the offset online (SlidingWindowBa::Options::calibrate_disparity_offset) and the trajectory
// comes close to the exact rig's; without, the far points' depths make the scale wrong.
// Measured (rover, 250 frames, seed 5): exact rig ATE 0.0253 m; 0.3 px rig 0.0340 m calibrated
// (0.321 px), 0.1117 m without. Bounds: calibrated < 0.45x without and < 1.8x exact.
// System::Finish then re-solves every keyframe with the offset free (ba.final_ba "rig_offset",
// the default): the keyframes made before the offset was known lose their scale error too.
// Measured: 0.0108 m after it (0.295 px), below the exact rig's online 0.0253 m (the global BA
// also spreads each observation over every keyframe). Bounds: no worse than online, 1.5x the
// measured value; on the exact rig Finish does not run the global BA (no offset was found).
TEST(SystemE2e, CalibratesTheRigsDisparityOffset) {
  sim::SimOptions sim = RoverStretch(250, 5);
  const SystemRun exact = RunSystem(sim::SyntheticSequence(sim), SystemOptions(), true);
  sim.right_cx_error_px = 0.3;
  const sim::SyntheticSequence seq(sim);
  const SystemRun calibrated = RunSystem(seq, SystemOptions(), true);
  SystemOptions off;
  off.ba.ba.calibrate_disparity_offset = false;
  const SystemRun uncalibrated = RunSystem(seq, off);
  ASSERT_TRUE(exact.eval.ok && calibrated.eval.ok && uncalibrated.eval.ok);
  ASSERT_TRUE(calibrated.disparity_offset_px.has_value());
  std::cout << "[ measured ] rover 250 frames: exact rig ATE " << exact.eval.ate.translation.rmse
            << " m (offset " << exact.disparity_offset_px.value_or(-1) << " px); 0.3 px rig "
            << calibrated.eval.ate.translation.rmse << " m calibrated ("
            << *calibrated.disparity_offset_px << " px), "
            << uncalibrated.eval.ate.translation.rmse << " m without" << std::endl;
  EXPECT_EQ(exact.disparity_offset_px.value_or(-1), 0.0);
  EXPECT_NEAR(*calibrated.disparity_offset_px, 0.3, 0.06);
  EXPECT_LT(calibrated.eval.ate.translation.rmse, 0.45 * uncalibrated.eval.ate.translation.rmse);
  EXPECT_LT(calibrated.eval.ate.translation.rmse, 1.8 * exact.eval.ate.translation.rmse);
  EXPECT_EQ(calibrated.trajectory.size(), seq.size());
  // After the run.
  ASSERT_TRUE(calibrated.finished_eval && calibrated.finished_eval->ok);
  std::cout << "[ measured ] after Finish: 0.3 px rig "
            << calibrated.finished_eval->ate.translation.rmse << " m ("
            << calibrated.finished_offset_px.value_or(-1) << " px)" << std::endl;
  EXPECT_FALSE(exact.refined) << "an exact rig: no offset found, no global BA";
  EXPECT_EQ(exact.finished_eval->ate.translation.rmse, exact.eval.ate.translation.rmse);
  EXPECT_TRUE(calibrated.refined);
  EXPECT_NEAR(calibrated.finished_offset_px.value_or(-1), 0.3, 0.03);
  EXPECT_LE(calibrated.finished_eval->ate.translation.rmse, calibrated.eval.ate.translation.rmse);
  EXPECT_LT(calibrated.finished_eval->ate.translation.rmse, 1.5 * 0.0108);
}

// A rig's offset known from an earlier run (what `dala run` prints: --set
// ba.calibrate_disparity_offset=0 --set ba.disparity_offset_px=X) is used from the first frame:
// the 0.3 px rig then tracks like the exact one online, where the rig left at 0 does not.
// Measured (rover 250 frames, seed 5): exact 0.0253 m, known 0.3 px 0.0274 m, 0 px 0.1117 m.
// Bounds: known < 1.2x exact, and < 0.5x the rig left at 0.
TEST(SystemE2e, AKnownDisparityOffsetIsUsedFromTheFirstFrame) {
  sim::SimOptions sim = RoverStretch(250, 5);
  const SystemRun exact = RunSystem(sim::SyntheticSequence(sim), SystemOptions());
  sim.right_cx_error_px = 0.3;
  const sim::SyntheticSequence seq(sim);
  SystemOptions known;
  known.ba.ba.calibrate_disparity_offset = false;
  known.ba.ba.disparity_offset_px = 0.3;
  const SystemRun with_known = RunSystem(seq, known);
  known.ba.ba.disparity_offset_px = 0.0;
  const SystemRun with_zero = RunSystem(seq, known);
  ASSERT_TRUE(exact.eval.ok && with_known.eval.ok && with_zero.eval.ok);
  std::cout << "[ measured ] rover 250 frames: exact " << exact.eval.ate.translation.rmse
            << " m, known 0.3 px " << with_known.eval.ate.translation.rmse << " m, 0 px "
            << with_zero.eval.ate.translation.rmse << " m" << std::endl;
  EXPECT_EQ(with_known.disparity_offset_px.value_or(-1), 0.3);
  EXPECT_LT(with_known.eval.ate.translation.rmse, 1.2 * exact.eval.ate.translation.rmse);
  EXPECT_LT(with_known.eval.ate.translation.rmse, 0.5 * with_zero.eval.ate.translation.rmse);
}

// The paper's filters on the same measurements: stereo EKF, and the bearing-only mono EKF whose
// scale comes from the stereo visual motion (dead reckoning, as on the paper's robots:
// mono_stereo_motion).
TEST(SystemE2e, RoverStretchEkfStereoAndMono) {
  const sim::SyntheticSequence seq(RoverStretch(100, 7));
  for (const char* mode : {"stereo", "mono"}) {
    SystemOptions options;
    options.estimator = "ekf";
    options.mode = mode;
    // Mode "mono" alone is one camera now; the paper's setting is mono_stereo_motion.
    options.mono_stereo_motion = options.mode == "mono";
    const SystemRun run = RunSystem(seq, options);
    ASSERT_TRUE(run.eval.ok) << run.eval.error;
    EXPECT_EQ(run.trajectory.size(), seq.size());
    const double fraction = run.eval.ate.translation.rmse / seq.PathLength();
    std::cout << "[ measured ] ekf/" << mode << " rover 100 frames, path " << seq.PathLength()
              << " m, ATE " << run.eval.ate.translation.rmse << " m (" << 100 * fraction
              << " %)" << std::endl;
    testing::ExpectWithinBound(std::string("ekf/") + mode + " ATE / path, rover 100 frames",
                               100 * fraction, options.mode == "stereo" ? 0.0422 : 0.0332, "%");
  }
}

TEST(SystemE2e, UnsupportedCombinationIsAClearError) {
  sim::SimOptions sim;
  sim.frames = 2;
  const sim::SyntheticSequence seq(sim);
  // A rig that does not suit the estimator's mode is refused with a clear message.
  SystemOptions options;
  options.estimator = "ba";
  options.mode = "mono";
  EXPECT_NO_THROW(System(seq.rig(), options));
  StereoRig mono_rig = seq.rig();
  mono_rig.baseline = 0.0;
  options.mode = "stereo";
  try {
    MakeEstimator(mono_rig, options);
    ADD_FAILURE() << "ba/stereo on a monocular rig should be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("needs a stereo rig"), std::string::npos) << e.what();
  }
  options.mode = "mono";
  options.mono_stereo_motion = true;  // An option of the mono EKF only.
  try {
    System system(seq.rig(), options);
    ADD_FAILURE() << "ba/mono with mono_stereo_motion should be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mono_stereo_motion is an option of the mono EKF"),
              std::string::npos)
        << e.what();
  }
}

using testing::ReadAll;

// `dala run` twice on the same rendered folder: identical trajectory files, and the report has
// the keys scripts rely on.
TEST(SystemE2e, DalaRunIsDeterministicAndWritesEveryOutput) {
  testing::TempDir dir;
  sim::WriteSyntheticDataset(RoverStretch(40, 9), dir / "seq", false);
  for (const char* out : {"a", "b"}) {
    const testing::DalaCliResult r = testing::RunDala(
        "run " + (dir / "seq") + " --out " + (dir / out) + " --progress=false", dir / out);
    ASSERT_EQ(r.status, 0) << r.log();
  }
  for (const char* f : {"trajectory.txt", "trajectory_kitti.txt", "map.ply", "map.dmap",
                        "report.json", "trajectory.png", "memory.png"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / (std::string("a/") + f))) << f;
  }
  const std::string a = ReadAll(dir / "a/trajectory.txt");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, ReadAll(dir / "b/trajectory.txt"));
  EXPECT_EQ(ReadAll(dir / "a/map.dmap"), ReadAll(dir / "b/map.dmap"));
  EXPECT_EQ(ReadTrajectory(dir / "a/trajectory.txt").size(), 40u);
  const std::string report = ReadAll(dir / "a/report.json");
  for (const char* key : {"\"summary\"", "\"ate\"", "\"rmse\"", "\"fps\"", "\"ms_p95\"",
                          "\"frames\"", "\"options\"", "\"peak_rss_mb\"", "\"rss_mb\""}) {
    EXPECT_NE(report.find(key), std::string::npos) << key;
  }
  const cv::Mat memory = cv::imread(dir / "a/memory.png");
  EXPECT_GT(memory.rows, memory.cols / 2) << "two charts, one above the other";
}

TEST(SystemE2e, DalaRunReportsBadInputClearly) {
  testing::TempDir dir;
  const testing::DalaCliResult missing =
      testing::RunDala("run " + (dir / "nothing_here") + " --out " + (dir / "out"), dir / "log");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.log().find("nothing_here"), std::string::npos) << missing.log();
  EXPECT_FALSE(std::filesystem::exists(dir / "out/trajectory.txt"));
  // Unknown option key: exit 2 and the message lists the known keys.
  const testing::DalaCliResult unknown =
      testing::RunDala("run x --out y --set ba.no_such=1", dir / "log2");
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.log().find("ba.window_size"), std::string::npos) << unknown.log();
}

}  // namespace
}  // namespace dala
