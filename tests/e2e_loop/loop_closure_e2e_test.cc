// Loop closure end to end: dala::System (frontend place recognition + sliding-window BA with
// pose-graph correction) on rendered sequences with exact ground truth.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "backend/system.h"
#include "core/error.h"
#include "core/eval/evaluate.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/small_loop_drive.h"
#include "tests/test_util.h"

namespace dala {
namespace {

struct LoopRun {
  EvalResult eval;         // Final trajectory, every frame.
  EvalResult before_loop;  // Frames before the first loop: the trajectory just before it...
  EvalResult after_loop;   // ...and the same frames in the final trajectory.
  int loops_detected = 0;
  int loops_closed = 0;
  int lost = 0;
  // Keyframes whose loop was not closed and that added no place-recognition entry, and those
  // with a pose that the System did not record for the saved map (System::keyframes()).
  int refused_loops_without_place = 0;
  int refused_loops_not_saved = 0;
  // Keyframes whose loop closed and whose place the old keyframe holds (no entry added).
  int closed_loops_holding_old_place = 0;
  // Loops not closed that do not say why (FrameStats::loop_not_closed).
  int refused_loops_without_reason = 0;
  // The fewest keyframes from one loop detected to the next (-1: fewer than two loops).
  int min_keyframes_between_loops = -1;
};

Trajectory Prefix(const Trajectory& t, size_t n) {
  Trajectory out = t;
  out.poses.resize(std::min(n, out.poses.size()));
  return out;
}

// Runs the System over the rendered sequence. Until the first loop the run is the run without
// loop closure (deterministic), so the trajectory just before the first loop is the open-loop
// estimate of those frames; it is compared with the same frames after the loop closure.
LoopRun RunSystem(const sim::SyntheticSequence& seq, const SystemOptions& options,
                  AlignmentType alignment = AlignmentType::kSE3) {
  EvalOptions eval;
  eval.alignment = alignment;
  System system(seq.rig(), options);
  LoopRun run;
  Trajectory before, previous_trajectory;
  size_t first_loop = 0;
  int places = 0;
  std::vector<FrameId> refused_with_pose;
  int keyframes = 0;
  std::optional<int> last_loop_keyframe;
  for (size_t i = 0; i < seq.size(); ++i) {
    const TrackResult r = system.Track(seq.Render(i));
    run.lost += r.status == TrackingStatus::kLost;
    const FrameStats& s = system.stats().back();
    keyframes += s.keyframe;
    if (s.loop) {
      if (last_loop_keyframe) {
        const int between = keyframes - *last_loop_keyframe;
        if (run.min_keyframes_between_loops < 0 || between < run.min_keyframes_between_loops) {
          run.min_keyframes_between_loops = between;
        }
      }
      last_loop_keyframe = keyframes;
    }
    run.refused_loops_without_reason += s.loop && !s.loop_closed && s.loop_not_closed.empty();
    run.refused_loops_without_place += s.loop && !s.loop_closed && s.places == places;
    run.closed_loops_holding_old_place += s.loop_closed && s.places == places;
    if (s.loop && !s.loop_closed && s.valid) refused_with_pose.push_back(s.frame);
    places = s.places;
    if (s.loop && run.loops_detected == 0) {
      first_loop = i;
      before = previous_trajectory;  // The open-loop estimate of the frames before it.
    }
    if (run.loops_detected == 0 && !s.loop) previous_trajectory = system.trajectory();
    run.loops_detected += s.loop;
    run.loops_closed += s.loop_closed;
  }
  std::set<FrameId> saved;
  for (const SavedKeyframe& kf : system.keyframes()) saved.insert(kf.frame);
  for (const FrameId& f : refused_with_pose) run.refused_loops_not_saved += saved.count(f) == 0;
  const Trajectory final_trajectory = system.trajectory();
  run.eval = Evaluate(seq.ground_truth(), final_trajectory, eval);
  if (run.loops_detected > 0) {
    run.before_loop = Evaluate(seq.ground_truth(), before, eval);
    run.after_loop = Evaluate(seq.ground_truth(), Prefix(final_trajectory, first_loop), eval);
  }
  return run;
}

// The small loop (~125 m) at 3 Hz and 480x320, a little more than one lap: the revisit is
// recognised, the pose graph corrects the trajectory, and the ATE of the lap drops well below
// the open-loop one.
TEST(LoopClosureE2e, SmallLoopIsClosedAndAteDrops) {
  const sim::SyntheticSequence seq(SmallLoopAt3Hz(160));
  const LoopRun run = RunSystem(seq, SystemOptions());
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  ASSERT_GE(run.loops_detected, 1);
  ASSERT_TRUE(run.before_loop.ok && run.after_loop.ok);
  const double path = seq.PathLength();
  const double open = run.before_loop.ate.translation.rmse;
  const double closed = run.after_loop.ate.translation.rmse;
  std::cout << "[ measured ] small_loop " << seq.size() << " frames, path " << path
            << " m: ATE (frames before the first loop) open loop " << open << " m, after loop "
            << "closure " << closed << " m; whole run " << run.eval.ate.translation.rmse << " m ("
            << 100 * run.eval.ate.translation.rmse / path << " %); loops detected "
            << run.loops_detected << ", closed " << run.loops_closed << std::endl;
  EXPECT_EQ(run.lost, 0);
  EXPECT_EQ(run.loops_closed, run.loops_detected);
  EXPECT_LT(closed, 0.7 * open);                            // Measured: open 0.049 m, closed 0.029 m.
  testing::ExpectWithinBound("ba/stereo ATE / path, small loop with its loops closed",
                             100 * run.eval.ate.translation.rmse / path, 0.0208, "%");
}

// One entry per place and keyframe culling (issue 14, memory bounded by the place): the small
// loop at 3 Hz driven for 1.5 laps. After the revisit is recognised, the second lap's keyframes
// are held by the first lap's place-recognition entries: the keyframes go on, the stored places
// (and the saved map's keyframes) nearly stop, the held keyframes leave the map once they have
// left the window (culling), and the trajectory is as good as with an entry and a keyframe each.
TEST(LoopClosureE2e, RevisitStoresNoNewPlacesAndCullsItsKeyframes) {
  const sim::SyntheticSequence seq(SmallLoopAt3Hz(225));
  struct Variant {
    bool one_per_place, cull;
    double ate = 0;
  };
  std::vector<Variant> variants = {{true, true}, {true, false}, {false, false}};
  for (Variant& v : variants) {
    SystemOptions options;
    options.frontend.loop.one_entry_per_place = v.one_per_place;
    options.ba.cull_held_keyframes = v.cull;
    System system(seq.rig(), options);
    int keyframes_at_loop = -1, places_at_loop = -1, in_map_at_loop = -1, keyframes = 0;
    for (size_t i = 0; i < seq.size(); ++i) {
      system.Track(seq.Render(i));
      const FrameStats& s = system.stats().back();
      keyframes += s.keyframe;
      if (s.loop && keyframes_at_loop < 0) {
        keyframes_at_loop = keyframes;
        places_at_loop = s.places;
        in_map_at_loop = s.keyframes_in_map;
      }
    }
    ASSERT_GE(keyframes_at_loop, 0) << "the revisit was not recognised";
    const int new_keyframes = keyframes - keyframes_at_loop;
    const int new_places = static_cast<int>(system.places()) - places_at_loop;
    const int new_in_map = system.stats().back().keyframes_in_map - in_map_at_loop;
    const EvalResult eval = Evaluate(seq.ground_truth(), system.trajectory(), EvalOptions());
    ASSERT_TRUE(eval.ok) << eval.error;
    ASSERT_EQ(system.trajectory().size(), seq.size()) << "every frame keeps its pose";
    v.ate = eval.ate.translation.rmse;
    std::cout << "[ measured ] one entry per place " << v.one_per_place << ", culling " << v.cull
              << ": after the first loop " << new_keyframes << " keyframes made, " << new_in_map
              << " more in the map, " << new_places << " places stored; "
              << system.keyframes().size() << " saved keyframes of " << keyframes << "; ATE "
              << v.ate << " m" << std::endl;
    ASSERT_GE(new_keyframes, 20);
    if (v.one_per_place) {
      EXPECT_LE(new_places, new_keyframes / 5);
      EXPECT_LT(system.keyframes().size(), static_cast<size_t>(keyframes - new_keyframes / 2));
    } else {
      EXPECT_EQ(new_places, new_keyframes);
    }
    if (v.cull) {
      // What stays: the places stored, the window with its held keyframes, and the odd keyframe
      // whose place was not checked (measured: 14 = 5 places + 8 + 1).
      EXPECT_LE(new_in_map,
                new_places + options.ba.ba.window_size + 3);  // Stereo: no held keyframes.
      EXPECT_LE(new_in_map, new_keyframes / 3);
    } else {
      EXPECT_EQ(new_in_map, new_keyframes);
    }
  }
  EXPECT_LT(variants[0].ate, 1.2 * variants[2].ate);
  EXPECT_LT(variants[1].ate, 1.2 * variants[2].ate);
}

// One camera: the small loop (500 frames, ~124 m) from the left images. The revisit is
// recognised and closed over Sim(3) (the current keyframe placed by PnP on the old landmarks,
// the scale from the recognised landmarks mapped on both sides). Measured: Sim(3) ATE 0.0639 m
// with the loop, 0.164 m with the same run not corrected (`ba.loop_correct=0`). Bounds: 1.5x
// the best recorded, and closed below not corrected.
TEST(LoopClosureE2e, MonoSmallLoopIsClosedOverSim3) {
  sim::SimOptions sim;
  sim.preset = "small_loop";
  sim.seed = 1;
  const sim::SyntheticSequence seq(sim);
  SystemOptions options;
  options.mode = "mono";
  const LoopRun run = RunSystem(seq, options, AlignmentType::kSim3);
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  std::cout << "[ measured ] mono small_loop " << seq.size() << " frames: Sim(3) ATE "
            << run.eval.ate.translation.rmse << " m; loops detected " << run.loops_detected
            << ", closed " << run.loops_closed << std::endl;
  EXPECT_GE(run.loops_closed, 1);
  testing::ExpectWithinBound("ba/mono small loop closed over Sim(3), Sim(3) ATE",
                             run.eval.ate.translation.rmse, 0.0639, "m");
  SetSystemOption("ba.loop_correct=false", &options);
  const LoopRun open = RunSystem(seq, options, AlignmentType::kSim3);
  ASSERT_TRUE(open.eval.ok) << open.eval.error;
  std::cout << "[ measured ] not corrected: Sim(3) ATE " << open.eval.ate.translation.rmse << " m"
            << std::endl;
  EXPECT_LT(run.eval.ate.translation.rmse, open.eval.ate.translation.rmse);
}

// One camera's loops meet the stereo rig's orientation gate (loop.gate_rotation_deg +
// loop.gate_rotation_deg_per_m x path, backend/mono/loop_turn_gate.h). The small loop at 5 Hz,
// 480x320, 300 frames: its right loops turn the camera by 0.2-0.6 deg, well inside the default
// 10 deg, and all close. A gate of 1e-6 deg, given by the same keys as the stereo rig's, refuses
// every one of them (with one refused the next ones turn by as little as 0.0005 deg): the keys
// reach the estimator's Sim(3) loop closure, and no loop is closed (the refused loops' old
// landmarks stay unused, their points take back their ids). loop.spatial_gate=false switches the
// gate off with the place recognition's own gates: loops close again. The measured values are
// printed ([ measured ]) and in docs/results.md, stop 53.
TEST(LoopClosureE2e, OneCamerasLoopsMeetTheOrientationGate) {
  sim::SimOptions sim;
  sim.preset = "small_loop";
  sim.fps = 5.0;
  sim.frames = 300;
  sim.width = 480;
  sim.height = 320;
  sim.fx = sim.fy = 290.0;
  const sim::SyntheticSequence seq(sim);
  SystemOptions options;
  options.mode = "mono";
  const LoopRun run = RunSystem(seq, options, AlignmentType::kSim3);
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  SetSystemOption("loop.gate_rotation_deg=0.000001", &options);
  SetSystemOption("loop.gate_rotation_deg_per_m=0", &options);
  const LoopRun gated = RunSystem(seq, options, AlignmentType::kSim3);
  ASSERT_TRUE(gated.eval.ok) << gated.eval.error;
  std::cout << "[ measured ] mono small_loop 5 Hz " << seq.size() << " frames: loops closed "
            << run.loops_closed << " of " << run.loops_detected << ", Sim(3) ATE "
            << run.eval.ate.translation.rmse << " m; gate 1e-6 deg: closed " << gated.loops_closed
            << " of " << gated.loops_detected << ", Sim(3) ATE " << gated.eval.ate.translation.rmse
            << " m, " << gated.lost << " frames lost" << std::endl;
  EXPECT_GE(run.loops_closed, 1);
  EXPECT_EQ(run.loops_closed, run.loops_detected);
  // A closed loop's keyframe leaves its place to the old keyframe (one entry per place), and the
  // next keyframes_between_loops keyframes are not searched.
  EXPECT_GE(run.closed_loops_holding_old_place, 1);
  EXPECT_GT(run.min_keyframes_between_loops, options.frontend.loop.keyframes_between_loops);
  EXPECT_GE(gated.loops_detected, 1);
  EXPECT_EQ(gated.loops_closed, 0);
  // A refused loop says why in its frame's note, and the next keyframe searches again.
  EXPECT_EQ(gated.refused_loops_without_reason, 0);
  EXPECT_GE(gated.min_keyframes_between_loops, 1);
  EXPECT_LE(gated.min_keyframes_between_loops, options.frontend.loop.keyframes_between_loops);
  // A refused loop's points take back their ids (Frontend::ReturnLoopIds): their tracks go on
  // in the current map, and no frame is lost for the refusal (the frame is placed by its points
  // under their current ids: loops at consecutive keyframes relabel most of them). The old
  // keyframe does not hold the place of a keyframe whose loop was refused: that keyframe stores
  // its own entry.
  EXPECT_EQ(gated.lost, 0);
  EXPECT_EQ(gated.refused_loops_without_place, 0);
  EXPECT_EQ(gated.refused_loops_not_saved, 0);
  EXPECT_LT(run.eval.ate.translation.rmse, gated.eval.ate.translation.rmse);
  SetSystemOption("loop.spatial_gate=false", &options);
  const LoopRun ungated = RunSystem(seq, options, AlignmentType::kSim3);
  ASSERT_TRUE(ungated.eval.ok) << ungated.eval.error;
  std::cout << "[ measured ] the same 1e-6 deg gate with loop.spatial_gate=false: closed "
            << ungated.loops_closed << " of " << ungated.loops_detected << std::endl;
  EXPECT_GE(ungated.loops_closed, 1);
}

// false_loop at 2 Hz, 480x320, up to x = 160 m: the stretch x = 140-160 m is a copy of
// x = 40-60 m (tests/frontend/loop shows matcher and PnP accept it without the spatial gate).
// No loop may be accepted.
TEST(LoopClosureE2e, LookAlikeStreetClosesNoLoop) {
  sim::SimOptions sim;
  sim.preset = "false_loop";
  sim.fps = 2.0;
  sim.frames = 160;  // 1 m per frame, x = 0 .. 159 m.
  sim.width = 480;
  sim.height = 320;
  sim.fx = sim.fy = 290.0;
  const sim::SyntheticSequence seq(sim);
  SystemOptions options;
  options.frontend.loop.min_frame_gap = 20;
  const LoopRun run = RunSystem(seq, options);
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  std::cout << "[ measured ] false_loop " << seq.size() << " frames: ATE "
            << run.eval.ate.translation.rmse << " m, loops " << run.loops_detected << std::endl;
  EXPECT_EQ(run.loops_detected, 0);
  EXPECT_EQ(run.loops_closed, 0);
  // A false loop closed would bend the street (159 m).
  testing::ExpectWithinBound("ba/stereo look-alike street, no loop accepted, ATE",
                             run.eval.ate.translation.rmse, 0.0872, "m");
}

// A slow rig at 30 fps passes loop.min_frame_gap (100 frames) within 4 m of the same street: the
// old keyframe is still the current map's view and verifies as a "loop" (frame 176 with frame 75
// here before the stereo path criterion, PlaceRecognition::LeftAndCameBack). Closing it bent the
// window (1.5 m ATE over 600 frames with denser keyframes, docs/results.md stop 48). The path
// never returns: no loop is right.
TEST(LoopClosureE2e, ASlowRigClosesNoLoopWithItsOwnMap) {
  sim::SimOptions sim;
  sim.preset = "small_loop";
  sim.fps = 30.0;
  sim.frames = 200;  // ~0.08 m per frame, 17 m of street.
  sim.seed = 3;
  const sim::SyntheticSequence seq(sim);
  const LoopRun run = RunSystem(seq, SystemOptions());
  ASSERT_TRUE(run.eval.ok) << run.eval.error;
  std::cout << "[ measured ] small_loop 30 fps " << seq.size() << " frames: ATE "
            << run.eval.ate.translation.rmse << " m, loops " << run.loops_detected << std::endl;
  EXPECT_EQ(run.loops_detected, 0);
  EXPECT_EQ(run.loops_closed, 0);
}

// The loop options are in the one option table (YAML, --set, --dump-config, report.json).
TEST(LoopClosureE2e, LoopOptionsAreSettableAndValidated) {
  SystemOptions options;
  SetSystemOption("loop.enable=0", &options);
  EXPECT_FALSE(options.frontend.loop.enable);
  SetSystemOption("loop.min_inliers=40", &options);
  EXPECT_EQ(options.frontend.loop.min_inliers, 40);
  SetSystemOption("ba.loop_correct=false", &options);
  EXPECT_FALSE(options.ba.loop.enable);
  SetSystemOption("loop.gate_fraction=0.2", &options);
  EXPECT_DOUBLE_EQ(options.frontend.loop.gate_fraction, 0.2);
  SystemOptions bad = options;
  EXPECT_THROW(SetSystemOption("loop.min_inliers=3", &bad), Error);  // < the PnP's minimum.
  bad = options;
  EXPECT_THROW(SetSystemOption("loop.gate_radius_m=0", &bad), Error);
  EXPECT_THROW(SetSystemOption("loop.no_such_key=1", &bad), Error);
  const std::string yaml = SystemOptionsToYaml(options);
  EXPECT_NE(yaml.find("loop:\n  enable: 0"), std::string::npos) << yaml;
  EXPECT_EQ(SystemOptionsToJson(options)["loop"]["min_inliers"], 40);
}

}  // namespace
}  // namespace dala
