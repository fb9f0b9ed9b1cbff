// End to end from ONE camera: dala::System with the monocular sliding-window BA on rendered
// sequences with exact ground truth (left images only) and on the real KITTI 06 frames 0-50
// (../shared/data), evaluated after a Sim(3) alignment (the scale of one camera is free); and
// the relocalisation after lost frames in mono and in stereo.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>

#include "backend/system.h"
#include "backend/system_ensemble.h"
#include "core/eval/evaluate.h"
#include "core/eval/scale_along_path.h"
#include "core/io/dataset.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/test_util.h"

namespace dala {
namespace {

// Bounds: 1.5x the best value recorded for each run (testing::ExpectWithinBound; the table in
// docs/reliability.md), not re-set when a change makes a run worse. Runs are bit-identical
// (deterministic), so no noise margin is added. The history of these numbers is in
// docs/results.md.
constexpr double kRoverAtePercentBest = 0.0598;        // 0.0168 m over 28.0 m.
constexpr double kBlackAtePercentBest = 0.0830;
// Three draws of the rover stretch fused: 0.0124 m (draws 0.0251, 0.0127, 0.0102 m).
constexpr double kRoverFusedAtePercentBest = 0.0441;
constexpr double kKittiAteMetresBest = 0.0308;
// Median of draws 0-2; without relocalisation (draw 0) 0.0541 %.
constexpr double kStereoBlackAtePercentBest = 0.0378;
constexpr double kJerkSeed4AteMetresBest = 0.1725;  // fast 200 seed 4 (jerks).
constexpr double kJerkSeed7AteMetresBest = 0.0343;  // fast 200 seed 7 (a jerk at frame 90).
constexpr double kGapBridgedAteMetresBest = 0.0828;  // fast 200 seed 2, frames 60-67 dropped.
constexpr double kTurnStartAtePercentBest = 0.0550;    // 0.0185 m over 33.7 m (seed 2, 120).
constexpr double kSharpTurnStartAteMetresBest = 0.00419;  // fast seed 3 from 20, KITTI geometry.

struct MonoRun {
  Trajectory trajectory;
  EvalResult eval;
  int initialising = 0;  // Frames seen before the map existed.
  int first_pose = -1;   // Index of the frame whose Track first returned a valid pose.
  int lost_after = 0;    // Frames without a valid estimate after that.
  // Of them, those not reported as lost with the reason (status kLost, a note "lost...").
  int lost_without_reason = 0;
  std::vector<std::string> notes;
  std::map<int64_t, bool> keyframe;  // By timestamp: the frame became a keyframe.
};

SystemOptions MonoBa() {
  SystemOptions options;
  options.estimator = "ba";
  options.mode = "mono";
  return options;
}

template <typename NextFrame>
MonoRun RunFrames(const StereoRig& rig, size_t frames, const NextFrame& next, const Trajectory& gt,
                  const SystemOptions& options, AlignmentType alignment = AlignmentType::kSim3) {
  System system(rig, options);
  MonoRun run;
  for (size_t i = 0; i < frames; ++i) {
    const TrackResult r = system.Track(next(i));
    run.notes.push_back(system.stats().back().note);
    run.keyframe[system.stats().back().t_ns] = system.stats().back().keyframe && r.valid;
    if (r.status == TrackingStatus::kInitializing && !r.valid) ++run.initialising;
    if (r.valid && run.first_pose < 0) run.first_pose = static_cast<int>(i);
    if (run.first_pose >= 0 && !r.valid) {
      ++run.lost_after;
      run.lost_without_reason += r.status != TrackingStatus::kLost ||
                                 run.notes.back().rfind("lost", 0) != 0;
    }
  }
  run.trajectory = system.trajectory();
  EvalOptions eval;
  eval.alignment = alignment;
  run.eval = Evaluate(gt, run.trajectory, eval);
  return run;
}

MonoRun RunRendered(const sim::SyntheticSequence& seq, const SystemOptions& options,
                    const std::vector<size_t>& black_frames = {},
                    AlignmentType alignment = AlignmentType::kSim3) {
  return RunFrames(
      seq.rig(), seq.size(),
      [&](size_t i) {
        Frame f = seq.Render(i);
        if (std::count(black_frames.begin(), black_frames.end(), i)) f.left.setTo(0);
        return f;
      },
      seq.ground_truth(), options, alignment);
}

sim::SimOptions Preset(const char* name, int frames) {
  sim::SimOptions sim;
  sim.preset = name;
  sim.frames = frames;
  sim.seed = 1;
  return sim;
}

// The rover loop's first 150 frames (~37 m) from the left camera: initialised within a few
// frames, every frame after that tracked, and the Sim(3) ATE a small fraction of the path.
TEST(MonoE2e, RoverStretchMonoBa) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 150));
  const MonoRun run = RunRendered(seq, MonoBa());
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_GE(run.first_pose, 1);
  EXPECT_LE(run.first_pose, 10);
  EXPECT_EQ(run.lost_after, 0);
  EXPECT_EQ(run.trajectory.size(), seq.size());  // The frames before get their pose afterwards.
  const double fraction = run.eval.ate.translation.rmse / seq.PathLength();
  std::cout << "[ measured ] ba/mono rover 150 frames, path " << seq.PathLength()
            << " m, Sim(3) ATE " << run.eval.ate.translation.rmse << " m (" << 100 * fraction
            << " %), first pose at frame " << run.first_pose << std::endl;
  testing::ExpectWithinBound("ba/mono Sim(3) ATE / path, rover 150 frames", 100 * fraction,
                             kRoverAtePercentBest, "%");
}

// Three RANSAC draws of the rover stretch in one SystemEnsemble, fused (`dala run --draws 3`,
// backend/system_ensemble.h): the fused trajectory gives every frame a pose, is no farther from
// the truth than the worst of its draws, and stays within its bound.
TEST(MonoE2e, ThreeDrawsFusedAreNoWorseThanTheirWorst) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 150));
  SystemEnsembleOptions three;
  three.draws = 3;
  three.threads = 2;
  SystemEnsemble runs(seq.rig(), MonoBa(), three);  // `dala run --draws 3`.
  for (size_t i = 0; i < seq.size(); ++i) runs.Track(seq.Render(i));
  runs.Finish();
  const std::vector<Trajectory> draws = runs.Trajectories();
  EvalOptions eval;
  eval.alignment = AlignmentType::kSim3;
  double worst = 0.0;
  for (int k = 0; k < runs.size(); ++k) {
    const EvalResult draw = Evaluate(seq.ground_truth(), draws[k], eval);
    ASSERT_TRUE(draw.ok) << draw.error;
    std::cout << "[ measured ] ba/mono rover 150 frames, draw " << k << ": Sim(3) ATE "
              << draw.ate.translation.rmse << " m" << std::endl;
    worst = std::max(worst, draw.ate.translation.rmse);
  }
  FusedTrajectory fused;
  std::string why;
  ASSERT_TRUE(runs.Fuse(draws, runs.FusableDraws(draws), &fused, &why)) << why;
  EXPECT_EQ(fused.trajectory.size(), seq.size());
  const EvalResult result = Evaluate(seq.ground_truth(), fused.trajectory, eval);
  ASSERT_TRUE(result.ok) << result.error;
  const double fused_ate = result.ate.translation.rmse;
  std::cout << "[ measured ] ba/mono rover 150 frames, the three draws fused: Sim(3) ATE "
            << fused_ate << " m" << std::endl;
  EXPECT_LE(fused_ate, worst);
  testing::ExpectWithinBound("ba/mono Sim(3) ATE / path, rover 150 frames, 3 draws fused",
                             100 * fused_ate / seq.PathLength(), kRoverFusedAtePercentBest, "%");
}

// The fast preset's first 200 frames rendered with `seed`, run with one camera; the frames
// [gap_begin, gap_begin + gap_size) are never given (a camera that dropped them: the next frame
// comes 0.1 s x (gap_size + 1) after the last one).
MonoRun RunFast200(uint64_t seed, size_t gap_begin = 0, size_t gap_size = 0) {
  sim::SimOptions sim = Preset("fast", 200);
  sim.seed = seed;
  const sim::SyntheticSequence seq(sim);
  return RunFrames(
      seq.rig(), seq.size() - gap_size,
      [&](size_t i) { return seq.Render(i < gap_begin ? i : i + gap_size); }, seq.ground_truth(),
      MonoBa());
}

// Frames placed by a bridge from the last keyframe (their note says so).
int NumBridged(const MonoRun& run) {
  return static_cast<int>(
      std::count_if(run.notes.begin(), run.notes.end(), [](const std::string& n) {
        return n.rfind("bridged from keyframe", 0) == 0;
      }));
}

// The fast preset's heading wobbles (up to 1.5 rad/s) turn the camera further than the
// constant velocity foresees; the map-predicted frame-to-frame matching then keeps far unmapped
// points and loses the mapped ones (seed 7, frame 90: 86 inliers, 2 of them mapped out of 53).
// Matched again without a prior, the frame keeps its map (frontend.cc, TrackFromPrevious). Two
// seeds that lost the map before (seed 7: 11 frames, a new map and 0.63 m; seed 4: a bridged
// keyframe whose scale ran away, 3.6 m, then 0.38 m with the bridge's prior): no frame lost,
// and the scale along the path within 10 %.
TEST(MonoE2e, AJerkKeepsTheMap) {
  for (const auto& [seed, best] : {std::pair<uint64_t, double>{4, kJerkSeed4AteMetresBest},
                                   std::pair<uint64_t, double>{7, kJerkSeed7AteMetresBest}}) {
    const MonoRun run = RunFast200(seed);
    ASSERT_TRUE(run.eval.ok) << run.eval.error;
    EXPECT_EQ(run.lost_after, 0) << "seed " << seed;
    const ScaleAlongPath scale = MeasureScaleAlongPath(run.eval);
    std::cout << "[ measured ] ba/mono fast 200 seed " << seed << ": Sim(3) ATE "
              << run.eval.ate.translation.rmse << " m, " << run.lost_after
              << " frames lost, scale along the path " << scale.min << " to " << scale.max
              << std::endl;
    EXPECT_GT(scale.min, 0.9) << "seed " << seed;
    EXPECT_LT(scale.max, 1.1) << "seed " << seed;
    testing::ExpectWithinBound(
        "ba/mono fast 200 seed " + std::to_string(seed) + " (jerks), Sim(3) ATE",
        run.eval.ate.translation.rmse, best, "m");
  }
}

// Eight frames dropped (fast seed 2, frames 60-67: 8 m and a turn in 0.9 s): the frame after the
// gap sees too few mapped landmarks to be placed by them and is placed by its two-view geometry
// with the last keyframe (ba.mono_bridge), the step's length from the last speed. It becomes a
// keyframe whose new tracks only it and that keyframe see, and the bridge's relative pose stays
// a prior of the window solves (SlidingWindowBa::AddRelativePosePrior) so that the window cannot
// move it and its new landmarks by a similarity of their own (fast seed 4 before the frontend
// kept its map: 3.1x the scale, 3.61 m without the prior). No frame lost, the scale along the
// path within 10 %.
TEST(MonoE2e, AGapThatBreaksTheTracksIsBridged) {
  const MonoRun run = RunFast200(2, 60, 8);
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_LE(run.lost_after, 1);
  const int bridged = NumBridged(run);
  EXPECT_GE(bridged, 1);
  const ScaleAlongPath scale = MeasureScaleAlongPath(run.eval);
  std::cout << "[ measured ] ba/mono fast 200 seed 2 without frames 60-67: Sim(3) ATE "
            << run.eval.ate.translation.rmse << " m, " << run.lost_after << " frames lost, "
            << bridged << " bridged, scale along the path " << scale.min << " to " << scale.max
            << std::endl;
  EXPECT_GT(scale.min, 0.9);
  EXPECT_LT(scale.max, 1.1);
  testing::ExpectWithinBound("ba/mono fast 200 seed 2 without frames 60-67 (bridged), Sim(3) ATE",
                             run.eval.ate.translation.rmse, kGapBridgedAteMetresBest, "m");
}

// One camera started inside a turn (the rover loop's first bend, 1-2 deg of heading per frame):
// the first pair that passes the two-view test is often fitted best by a homography (the
// rotation dominates the image motion), whose decomposition has a spurious twin with every point
// in front. Four starts (two seeds) that initialise from such a pair: each must take its first
// pose within 10 frames and keep its Sim(3) ATE a small fraction of its 120 frames' path (a wrong
// decomposition gives 0.5-8 m here: docs/monocular.md, "Starting in a turn").
TEST(MonoE2e, StartInsideATurnKeepsTheShapeOfThePath) {
  struct Start {
    uint64_t seed;
    size_t first;
  };
  constexpr size_t kFrames = 120;
  double worst_percent = 0.0;
  for (const Start start : {Start{2, 100}, Start{2, 120}, Start{3, 115}, Start{3, 125}}) {
    sim::SimOptions sim = Preset("rover_loop", static_cast<int>(start.first + kFrames));
    sim.seed = start.seed;
    const sim::SyntheticSequence seq(sim);
    Trajectory gt;
    for (size_t i = start.first; i < seq.size(); ++i) {
      gt.poses.push_back(seq.ground_truth().poses[i]);
    }
    const MonoRun run = RunFrames(
        seq.rig(), kFrames, [&](size_t i) { return seq.Render(start.first + i); }, gt, MonoBa());
    ASSERT_TRUE(run.eval.ok) << run.eval.error;
    EXPECT_LE(run.first_pose, 10) << "seed " << start.seed << ", start " << start.first;
    EXPECT_EQ(run.lost_after, 0) << "seed " << start.seed << ", start " << start.first;
    const double percent = 100 * run.eval.ate.translation.rmse / gt.PathLength();
    std::cout << "[ measured ] ba/mono rover seed " << start.seed << " from frame " << start.first
              << ": path " << gt.PathLength() << " m, Sim(3) ATE " << run.eval.ate.translation.rmse
              << " m (" << percent << " %), first pose at frame " << run.first_pose << std::endl;
    worst_percent = std::max(worst_percent, percent);
  }
  testing::ExpectWithinBound("ba/mono Sim(3) ATE / path, worst of 4 starts in a turn",
                             worst_percent, kTurnStartAtePercentBest, "%");
}

// A car's camera (KITTI's image size, focal length and baseline) starting in a sharp turn: the
// rendered fast drive, seed 3, from frame 20, where the first pair has 8.7 deg of rotation
// against a 0.6 m step. RANSAC's essential matrix there is a wrong motion 72 deg off the truth
// that keeps almost every correspondence within its threshold; the map started from it put the
// first frame 2.2 m off and the 100 frames at 0.30 m. The initialiser samples the pair with
// MAGSAC++ as well and keeps its better-scored, different motion
// (backend/mono/refined_two_view.h): the first frame is placed like the rest.
TEST(MonoE2e, ASharpTurnAtTheStartIsNotTakenForASidestep) {
  constexpr size_t kFirst = 20, kFrames = 60;
  sim::SimOptions sim = Preset("fast", static_cast<int>(kFirst + kFrames));
  sim.seed = 3;
  sim.width = 1226;
  sim.height = 370;
  sim.fx = sim.fy = 707.0;
  sim.baseline = 0.537;
  const sim::SyntheticSequence seq(sim);
  Trajectory gt;
  for (size_t i = kFirst; i < seq.size(); ++i) gt.poses.push_back(seq.ground_truth().poses[i]);
  const MonoRun run = RunFrames(
      seq.rig(), kFrames, [&](size_t i) { return seq.Render(kFirst + i); }, gt, MonoBa());
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_LE(run.first_pose, 2);
  EXPECT_EQ(run.lost_after, 0);
  // The first frame after the alignment: within 0.1 m (RANSAC's map put it 2.2 m off).
  ASSERT_FALSE(run.eval.ate.translation_errors.empty());
  EXPECT_LT(run.eval.ate.translation_errors.front(), 0.1);
  std::cout << "[ measured ] ba/mono fast seed 3 in KITTI's geometry from frame " << kFirst
            << ": path " << gt.PathLength() << " m, Sim(3) ATE " << run.eval.ate.translation.rmse
            << " m, first frame " << run.eval.ate.translation_errors.front()
            << " m off, first pose at frame " << run.first_pose << std::endl;
  testing::ExpectWithinBound("ba/mono Sim(3) ATE, fast seed 3 from frame 20, KITTI's geometry",
                             run.eval.ate.translation.rmse, kSharpTurnStartAteMetresBest, "m");
}

// The frames between keyframes are tracked once, pose-only against landmarks that the later
// keyframes still refine; once their keyframe has left the window they are tracked again
// (ba.refine_frames, default with one camera). Nothing else changes (the keyframes are the same,
// to the bit), and those frames come closer to the ground truth. Measured on this preset:
// Sim(3) ATE 0.0364 m tracked once, 0.0319 m tracked again (docs/monocular.md).
TEST(MonoE2e, FramesBetweenKeyframesAreTrackedAgainAfterTheirKeyframeLeaves) {
  const sim::SyntheticSequence seq(Preset("flight", 150));
  SystemOptions once = MonoBa();
  once.ba.refine_frames = "off";
  const MonoRun before = RunRendered(seq, once);
  const MonoRun after = RunRendered(seq, MonoBa());
  ASSERT_TRUE(before.eval.ok && after.eval.ok) << before.eval.error << after.eval.error;
  ASSERT_EQ(before.trajectory.size(), after.trajectory.size());
  int moved = 0, keyframes = 0;
  for (size_t i = 0; i < after.trajectory.size(); ++i) {
    const StampedPose& a = before.trajectory.poses[i];
    const StampedPose& b = after.trajectory.poses[i];
    ASSERT_EQ(a.t_ns, b.t_ns);
    const bool same = a.T_w_c.matrix() == b.T_w_c.matrix();
    if (after.keyframe.at(b.t_ns)) {
      ++keyframes;
      EXPECT_TRUE(same) << "keyframe at frame " << i << " moved";
    } else {
      moved += same ? 0 : 1;
    }
  }
  std::cout << "[ measured ] ba/mono flight 150: Sim(3) ATE " << before.eval.ate.translation.rmse
            << " m tracked once, " << after.eval.ate.translation.rmse << " m tracked again ("
            << moved << " frames moved, " << keyframes << " keyframes)" << std::endl;
  EXPECT_GT(keyframes, 10);
  EXPECT_GT(moved, 20);
  EXPECT_LT(after.eval.ate.translation.rmse, 0.9 * before.eval.ate.translation.rmse);
}

TEST(MonoE2e, UnknownRefineFramesSettingIsAClearError) {
  SystemOptions options = MonoBa();
  options.ba.refine_frames = "sometimes";
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("ba.refine_frames must be mono, always or off"), std::string::npos) << why;
}

// Lost for longer than the map stays in view (80 black frames, ~20 m of a turning rover): after
// mono_reinit_after_lost_frames lost frames a new map is initialised and placed where the old one
// would continue (scale and heading across the gap guessed from the last speed). The frames
// after it are tracked again, and their own shape is accurate; lost frames get no pose.
// Measured: the re-initialisation starts within the gap and completes 12 frames after it (the
// frames since the reference are localised). Without the re-initialisation every frame after
// the gap is lost with an extrapolated pose (0.45 m).
TEST(MonoE2e, LongLossStartsANewMapThatContinuesTheTrajectory) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 300));
  std::vector<size_t> black;
  for (size_t i = 100; i < 180; ++i) black.push_back(i);
  const MonoRun run = RunRendered(seq, MonoBa(), black);
  int reinitialised = 0;
  for (const std::string& note : run.notes) reinitialised += note.rfind("re-initialised", 0) == 0;
  EXPECT_EQ(reinitialised, 1);
  // Every pose after the gap, aligned on its own.
  Trajectory after;
  const int64_t t_200 = seq.ground_truth().poses.at(200).t_ns;
  for (const StampedPose& p : run.trajectory.poses) {
    if (p.t_ns >= t_200) after.poses.push_back(p);
  }
  EXPECT_EQ(after.size(), 100u);
  EvalOptions eval;
  eval.alignment = AlignmentType::kSim3;
  const EvalResult r = Evaluate(seq.ground_truth(), after, eval);
  ASSERT_TRUE(r.ok) << r.error;
  std::cout << "[ measured ] ba/mono rover 300 frames, 80 black: " << run.trajectory.size()
            << " poses, frames 200-299 Sim(3) ATE " << r.ate.translation.rmse << " m" << std::endl;
  const int64_t t_100 = seq.ground_truth().poses.at(100).t_ns;
  const int64_t t_180 = seq.ground_truth().poses.at(180).t_ns;
  for (const StampedPose& p : run.trajectory.poses) {
    EXPECT_FALSE(p.t_ns >= t_100 && p.t_ns < t_180) << "a pose in the gap at " << p.t_ns;
  }
  testing::ExpectWithinBound("ba/mono frames 200-299 after 80 black, Sim(3) ATE",
                             r.ate.translation.rmse, 0.0233, "m");
}

// A camera turning on the spot gives no parallax: the map never starts, every frame says why,
// and no frame gets an invented pose.
TEST(MonoE2e, RotationNeverInitialisesAndSaysWhy) {
  const sim::SyntheticSequence seq(Preset("rotation", 40));
  const MonoRun run = RunRendered(seq, MonoBa());
  EXPECT_EQ(run.first_pose, -1);
  EXPECT_TRUE(run.trajectory.empty());
  EXPECT_EQ(run.initialising, 40);
  int parallax = 0;
  for (const std::string& note : run.notes) {
    EXPECT_EQ(note.rfind("initialising: ", 0), 0u) << note;
    parallax += note.find("parallax") != std::string::npos;
  }
  EXPECT_GT(parallax, 30) << run.notes.back();
}

// Three black frames in the middle: those frames are lost (not valid), and tracking resumes in
// the same map (the recovery relocalises against the last tracked keyframe), with the ATE of
// the frames after as good as before.
TEST(MonoE2e, TrackingResumesInTheSameMapAfterBlackFrames) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 100));
  const MonoRun run = RunRendered(seq, MonoBa(), {50, 51, 52});
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_GE(run.lost_after, 3);
  EXPECT_LE(run.lost_after, 5);
  EXPECT_EQ(run.lost_without_reason, 0);  // report.json says why each has no pose.
  const double fraction = run.eval.ate.translation.rmse / seq.PathLength();
  std::cout << "[ measured ] ba/mono rover 100 frames with 3 black ones: lost " << run.lost_after
            << ", Sim(3) ATE " << 100 * fraction << " % of the path" << std::endl;
  testing::ExpectWithinBound("ba/mono Sim(3) ATE / path, rover 100 with 3 black frames",
                             100 * fraction, kBlackAtePercentBest, "%");
}

TEST(MonoE2e, DeterministicTrajectory) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 40));
  const MonoRun a = RunRendered(seq, MonoBa());
  const MonoRun b = RunRendered(seq, MonoBa());
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  ASSERT_FALSE(a.trajectory.empty());
  for (size_t i = 0; i < a.trajectory.size(); ++i) {
    EXPECT_EQ(a.trajectory.poses[i].t_ns, b.trajectory.poses[i].t_ns);
    EXPECT_EQ(a.trajectory.poses[i].T_w_c.matrix(), b.trajectory.poses[i].T_w_c.matrix());
  }
}

// Real data: KITTI 06 frames 0-50, left images only (the right ones are never read).
TEST(MonoE2e, Kitti06LeftImagesMonoBa) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  DatasetOptions dataset_options;
  dataset_options.force_mono = true;
  auto dataset = OpenDataset(testing::SharedDataDir() + "/kitti06_0000-0050", dataset_options);
  ASSERT_FALSE(dataset->is_stereo());
  const MonoRun run = RunFrames(
      dataset->rig(), dataset->size(),
      [&](size_t) {
        Frame f;
        EXPECT_TRUE(dataset->Next(&f));
        return f;
      },
      *dataset->ground_truth(), MonoBa());
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  EXPECT_LE(run.first_pose, 10);
  EXPECT_EQ(run.lost_after, 0);
  EXPECT_EQ(run.trajectory.size(), dataset->size());
  std::cout << "[ measured ] ba/mono KITTI 06 0-50 left: Sim(3) ATE "
            << run.eval.ate.translation.rmse << " m over " << run.trajectory.size()
            << " frames, first pose at frame " << run.first_pose << std::endl;
  testing::ExpectWithinBound("ba/mono real KITTI 06 0-50 left images, Sim(3) ATE",
                             run.eval.ate.translation.rmse, kKittiAteMetresBest, "m");
}

}  // namespace
}  // namespace dala

namespace dala {
namespace {

// The same three black frames with the stereo BA: the frames after them find the last tracked
// keyframe's landmarks again (relocalisation without a prior, then PnP) and tracking resumes in
// the same map. Without the relocalisation (no local map handed to the frontend) the frames
// after the gap start new landmarks at the extrapolated pose. The ATE is the median over three
// RANSAC draws (ransac_order_seed 0, 1, 2): after the gap one draw moves it by up to 2x (eight
// draws: 0.0052-0.0096 m, docs/results.md), more than a change the bound is meant to catch.
TEST(RelocalisationE2e, StereoTrackingResumesInTheSameMapAfterBlackFrames) {
  const sim::SyntheticSequence seq(Preset("rover_loop", 100));
  SystemOptions stereo;
  std::vector<double> fractions;
  for (uint64_t draw = 0; draw < 3; ++draw) {
    stereo.ransac_order_seed = draw;
    const MonoRun with = RunRendered(seq, stereo, {50, 51, 52}, AlignmentType::kSE3);
    ASSERT_TRUE(with.eval.ok) << with.eval.error;
    EXPECT_EQ(with.lost_after, 3) << "draw " << draw;  // The black frames only.
    fractions.push_back(with.eval.ate.translation.rmse / seq.PathLength());
  }
  std::sort(fractions.begin(), fractions.end());
  const double median = fractions[1];
  stereo.ransac_order_seed = 0;
  stereo.frontend.local_map.enable = false;
  const MonoRun without = RunRendered(seq, stereo, {50, 51, 52}, AlignmentType::kSE3);
  ASSERT_TRUE(without.eval.ok) << without.eval.error;
  std::cout << "[ measured ] ba/stereo rover 100 frames with 3 black ones: SE(3) ATE over "
            << "draws 0-2 " << 100 * fractions[0] << " " << 100 * fractions[1] << " "
            << 100 * fractions[2]
            << " % of the path (without relocalisation, draw 0: lost " << without.lost_after << ", "
            << 100 * without.eval.ate.translation.rmse / seq.PathLength() << " %)" << std::endl;
  testing::ExpectWithinBound(
      "ba/stereo ATE / path, rover 100 with 3 black frames, median of 3 draws", 100 * median,
      kStereoBlackAtePercentBest, "%");
}

// Lost for 70 frames (black) while the camera drives on around the small loop, and the images
// return where the run started (the path's second lap): the last tracked keyframe is 17 m back
// and out of view, so only the keyframe database knows the place. The frames after the gap must
// be placed in the SAME map: frame 510 + k is where frame 10 + k was (the loop is periodic, the
// camera poses are identical), measured as the mean distance between the two estimates in
// metres (mono: in the map's unit divided by its scale to the ground truth, from frames 10-60).
// Without the database relocalisation (`loop.relocalise = 0`) mono starts a new map after 10
// lost frames and stereo continues at the extrapolated pose: 15.7 m and 24.0 m off.
struct GapRun {
  MonoRun run;
  double offset_m = 0.0;  // Mean |t(510 + k) - t(10 + k)| over k < 50, metres.
};

GapRun RunSmallLoopGap(const SystemOptions& options) {
  const sim::SyntheticSequence seq(Preset("small_loop", 560));
  std::vector<size_t> black;
  for (size_t i = 440; i < 510; ++i) black.push_back(i);
  GapRun out;
  out.run = RunRendered(seq, options, black,
                        options.mode == "mono" ? AlignmentType::kSim3 : AlignmentType::kSE3);
  std::map<int64_t, Eigen::Vector3d> t_at;
  for (const StampedPose& p : out.run.trajectory.poses) t_at[p.t_ns] = p.T_w_c.translation();
  bool complete = true;
  const auto at = [&](size_t i) -> Eigen::Vector3d {
    const auto it = t_at.find(seq.t_ns(i));
    if (it != t_at.end()) return it->second;
    complete = false;
    return Eigen::Vector3d::Zero();
  };
  const double scale = (at(60) - at(10)).norm() /
                       (seq.T_w_c0(60).translation() - seq.T_w_c0(10).translation()).norm();
  double sum = 0.0;
  for (size_t k = 0; k < 50; ++k) sum += (at(510 + k) - at(10 + k)).norm();
  out.offset_m = sum / 50.0 / scale;
  if (!complete) {
    ADD_FAILURE() << "a frame among 10-60 or 510-559 has no pose";
    out.offset_m = std::numeric_limits<double>::infinity();
  }
  return out;
}

constexpr double kMonoGapOffsetMetresBest = 0.0266;    // Without relocalisation: 15.7 m.
constexpr double kStereoGapOffsetMetresBest = 0.0252;  // Without relocalisation: 24.0 m.

TEST(RelocalisationE2e, MonoReturnsToAMappedPlaceAfterALongLoss) {
  const GapRun gap = RunSmallLoopGap(MonoBa());
  ASSERT_TRUE(gap.run.eval.ok) << gap.run.eval.error;
  EXPECT_EQ(gap.run.lost_after, 70);  // The black frames only.
  for (const std::string& note : gap.run.notes) {
    EXPECT_NE(note.rfind("re-initialised", 0), 0u) << "a new map was started: " << note;
  }
  std::cout << "[ measured ] ba/mono small_loop 560 frames, 440-509 black: frames 510-559 "
            << gap.offset_m << " m from frames 10-59, Sim(3) ATE " << gap.run.eval.ate.translation.rmse
            << " m" << std::endl;
  testing::ExpectWithinBound("ba/mono small_loop, frames 510-559 from frames 10-59 after 70 lost",
                             gap.offset_m, kMonoGapOffsetMetresBest, "m");
}

TEST(RelocalisationE2e, StereoReturnsToAMappedPlaceAfterALongLoss) {
  const GapRun gap = RunSmallLoopGap(SystemOptions());
  ASSERT_TRUE(gap.run.eval.ok) << gap.run.eval.error;
  EXPECT_EQ(gap.run.lost_after, 70);
  EXPECT_EQ(gap.run.trajectory.size(), 560u - 70u);  // Lost frames get no pose.
  std::cout << "[ measured ] ba/stereo small_loop 560 frames, 440-509 black: frames 510-559 "
            << gap.offset_m << " m from frames 10-59, SE(3) ATE " << gap.run.eval.ate.translation.rmse
            << " m" << std::endl;
  testing::ExpectWithinBound("ba/stereo small_loop, frames 510-559 from frames 10-59 after 70 lost",
                             gap.offset_m, kStereoGapOffsetMetresBest, "m");
}

}  // namespace
}  // namespace dala
