// SystemEnsemble: each draw is the run of its seed alone, whatever the number of threads; the
// draws are fused into the first one's world; mistakes are errors.
#include "backend/system_ensemble.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "core/geometry.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/test_util.h"

namespace dala {
namespace {

sim::SimOptions ShortRover(int frames = 40) {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = frames;
  sim.seed = 3;
  return sim;
}

SystemOptions Mono(uint64_t seed) {
  SystemOptions options;
  options.mode = "mono";
  options.ransac_order_seed = seed;
  return options;
}

SystemEnsembleOptions Draws(int draws, int threads) {
  SystemEnsembleOptions options;
  options.draws = draws;
  options.threads = threads;
  return options;
}

bool SamePoses(const Trajectory& a, const Trajectory& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a.poses[i].t_ns != b.poses[i].t_ns ||
        !a.poses[i].T_w_c.matrix().isApprox(b.poses[i].T_w_c.matrix(), 0.0)) {
      return false;
    }
  }
  return true;
}

// `runs` (`draws` draws of `options`, on its threads) against Systems run alone, one after
// the other, with the seeds options.ransac_order_seed + k: the same trajectories to the bit
// (the ensemble detects each frame once for all draws; each System alone detects its own).
// Returns the draws' trajectories.
std::vector<Trajectory> ExpectDrawsAreRunsAlone(const sim::SyntheticSequence& seq,
                                                const SystemOptions& options, int draws,
                                                SystemEnsemble* runs) {
  std::vector<std::unique_ptr<System>> alone;
  for (int k = 0; k < draws; ++k) {
    SystemOptions o = options;
    o.ransac_order_seed = options.ransac_order_seed + k;
    o.frontend.motion.seed = options.frontend.motion.seed + k;
    alone.push_back(std::make_unique<System>(seq.rig(), o));
  }
  for (size_t i = 0; i < seq.size(); ++i) {
    const Frame frame = seq.Render(i);
    const TrackResult r = runs->Track(frame);
    const TrackResult first = alone[0]->Track(frame);
    for (size_t k = 1; k < alone.size(); ++k) alone[k]->Track(frame);
    EXPECT_EQ(r.valid, first.valid) << "frame " << i;  // Track returns the first draw's result.
  }
  runs->Finish();
  for (auto& system : alone) system->Finish();
  EXPECT_EQ(runs->size(), draws);
  EXPECT_EQ(runs->wall_ms().size(), seq.size());
  const std::vector<Trajectory> trajectories = runs->Trajectories();
  for (int k = 0; k < draws; ++k) {
    EXPECT_EQ(runs->seed(k), options.ransac_order_seed + k);
    EXPECT_GT(trajectories[k].size(), seq.size() / 2) << "draw " << k << " barely initialised";
    EXPECT_TRUE(SamePoses(trajectories[k], alone[k]->trajectory())) << "draw " << k;
  }
  // Otherwise the seeds change nothing and the test above proves nothing.
  EXPECT_FALSE(SamePoses(trajectories[0], trajectories[1]));
  return trajectories;
}

// One camera: three draws on two threads (the first thread steps draws 0 and 2).
TEST(SystemEnsemble, EachDrawIsTheRunOfItsSeedWhateverTheThreads) {
  const sim::SyntheticSequence seq(ShortRover());
  SystemEnsemble two_threads(seq.rig(), Mono(5), Draws(3, 2));
  const std::vector<Trajectory> draws = ExpectDrawsAreRunsAlone(seq, Mono(5), 3, &two_threads);

  // Fused into the first draw's world and unit: its first pose stays near the first draw's.
  EXPECT_EQ(two_threads.FusionAlignment(), AlignmentType::kSim3);
  FusedTrajectory fused;
  std::string why;
  const std::vector<int> fusable = two_threads.FusableDraws(draws);
  ASSERT_EQ(fusable, (std::vector<int>{0, 1, 2}));
  ASSERT_TRUE(two_threads.Fuse(draws, fusable, &fused, &why)) << why;
  ASSERT_EQ(fused.alignments.size(), 3u);
  EXPECT_NEAR(fused.alignments[0].scale, 1.0, 0.05);
  const double path = seq.PathLength();
  EXPECT_LT((fused.trajectory.poses.front().T_w_c.translation() -
             draws[0].poses.front().T_w_c.translation())
                .norm(),
            0.01 * path);
}

// A stereo rig: the stereo matches are shared too.
TEST(SystemEnsemble, StereoDrawsAreTheRunsOfTheirSeeds) {
  const sim::SyntheticSequence seq(ShortRover(25));  // A stereo map from the first frame.
  SystemOptions stereo;
  stereo.ransac_order_seed = 2;
  SystemEnsemble runs(seq.rig(), stereo, Draws(2, 2));
  ExpectDrawsAreRunsAlone(seq, stereo, 2, &runs);
}

// One draw fuses to itself; a draw without a pose is not fusable.
TEST(SystemEnsemble, OneDrawIsItsOwnTrajectory) {
  const sim::SyntheticSequence seq(ShortRover());
  const SystemEnsemble runs(seq.rig(), Mono(0), Draws(2, 1));
  Trajectory some;
  for (int i = 0; i < 5; ++i)
    some.Add(i * 1000, MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(i, 0.1 * i * i, 0.0)));
  const std::vector<Trajectory> trajectories = {Trajectory(), some};
  const std::vector<int> fusable = runs.FusableDraws(trajectories);
  ASSERT_EQ(fusable, std::vector<int>{1});
  FusedTrajectory fused;
  std::string why;
  ASSERT_TRUE(runs.Fuse(trajectories, fusable, &fused, &why)) << why;
  EXPECT_EQ(fused.trajectory.size(), 5u);
  EXPECT_EQ(fused.runs, std::vector<int>(5, 1));
  EXPECT_FALSE(runs.Fuse(trajectories, {}, &fused, &why));
  EXPECT_EQ(why, "no draw to fuse");
}

// A stereo rig's draws are metric: they are brought onto one another rigidly.
TEST(SystemEnsemble, StereoDrawsFuseRigidly) {
  const sim::SyntheticSequence seq(ShortRover());
  const SystemEnsemble runs(seq.rig(), SystemOptions(), Draws(2, 2));
  EXPECT_EQ(runs.FusionAlignment(), AlignmentType::kSE3);
}

TEST(SystemEnsemble, MistakesAreErrorsThatChangeNothing) {
  const sim::SyntheticSequence seq(ShortRover());
  EXPECT_NE(testing::ErrorOf([&] {
              SystemEnsemble(seq.rig(), Mono(0), Draws(0, 1));
            }).find("draws must be >= 1, not 0"),
            std::string::npos);
  EXPECT_NE(testing::ErrorOf([&] {
              SystemEnsemble(seq.rig(), Mono(0), Draws(2, 0));
            }).find("threads must be >= 1, not 0"),
            std::string::npos);
  // A frame out of time order: every draw refuses it, the error reaches the caller, and the
  // next frame is tracked as if it had never come.
  SystemEnsemble runs(seq.rig(), Mono(0), Draws(2, 2));
  runs.Track(seq.Render(0));
  runs.Track(seq.Render(1));
  Frame earlier = seq.Render(2);
  earlier.t_ns = runs.first().stats().back().t_ns - 1;
  const std::string error = testing::ErrorOf([&] { runs.Track(earlier); });
  EXPECT_NE(error.find("comes before the previous frame"), std::string::npos) << error;
  runs.Track(seq.Render(2));
  for (int k = 0; k < runs.size(); ++k) EXPECT_EQ(runs.draw(k).stats().size(), 3u);

  // A System given the features of another frame refuses them, and goes on.
  System alone(seq.rig(), Mono(0));
  alone.Track(seq.Render(0));
  const Frame next = seq.Render(1);
  const FrameFeatures of_frame_0 =
      ComputeFrameFeatures(seq.Render(0), alone.rig(), alone.options().frontend, nullptr);
  const std::string wrong = testing::ErrorOf([&] { alone.Track(next, of_frame_0); });
  EXPECT_NE(wrong.find("the features given with frame 1 are those of frame 0"), std::string::npos)
      << wrong;
  alone.Track(next, ComputeFrameFeatures(next, alone.rig(), alone.options().frontend, nullptr));
  EXPECT_EQ(alone.stats().size(), 2u);
}

}  // namespace
}  // namespace dala
