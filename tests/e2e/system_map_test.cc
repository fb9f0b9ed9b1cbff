// System::keyframes / SaveMap / LoadMap on a rendered stereo stretch with exact ground truth.
#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <string>

#include "backend/system.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/test_util.h"

namespace dala {
namespace {

// The rendered rover loop (seed 11), `frames` long.
sim::SyntheticSequence RoverLoop(int frames) {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = frames;
  sim.seed = 11;
  return sim::SyntheticSequence(sim);
}

// Every frame of `seq` tracked by a System with `estimator` and the default options.
std::unique_ptr<System> TrackAll(const sim::SyntheticSequence& seq, const char* estimator) {
  SystemOptions options;
  options.estimator = estimator;
  auto system = std::make_unique<System>(seq.rig(), options);
  for (size_t i = 0; i < seq.size(); ++i) system->Track(seq.Render(i));
  return system;
}

TEST(SystemMap, SavedMapHoldsKeyframesLandmarksAndDescriptors) {
  const sim::SyntheticSequence seq = RoverLoop(40);
  for (const char* estimator : {"ba", "ekf"}) {
    const std::unique_ptr<System> owned = TrackAll(seq, estimator);
    const System& system = *owned;

    const std::vector<SavedKeyframe> keyframes = system.keyframes();
    ASSERT_GE(keyframes.size(), 3u) << estimator;
    EXPECT_EQ(keyframes.front().frame, FrameId(0));
    // The first frame is the world frame; every keyframe pose is close to the ground truth
    // (world = first camera in both), and keyframes are in time order.
    const Pose T_w0_gt_inv = seq.T_w_c0(0).inverse();
    for (size_t k = 0; k < keyframes.size(); ++k) {
      const SavedKeyframe& kf = keyframes[k];
      if (k > 0) {
        EXPECT_LT(keyframes[k - 1].t_ns, kf.t_ns);
      }
      const Pose T_gt = T_w0_gt_inv * seq.T_w_c0(kf.frame.value);
      EXPECT_LT((kf.T_w_c.translation() - T_gt.translation()).norm(), 0.15)
          << estimator << " keyframe " << kf.frame;
      EXPECT_GT(kf.points.size(), 50u);
      for (const SavedKeyframePoint& p : kf.points) {
        ASSERT_TRUE(p.landmark.valid());
        ASSERT_EQ(p.descriptor.size(), 121u);
      }
    }

    testing::TempDir dir;
    system.SaveMap(dir / "run.dmap");
    const SavedMap loaded = System::LoadMap(dir / "run.dmap");
    ASSERT_EQ(loaded.keyframes.size(), keyframes.size());
    EXPECT_EQ(loaded.descriptor_size, 121);
    for (size_t k = 0; k < keyframes.size(); ++k) {
      EXPECT_EQ(loaded.keyframes[k].frame, keyframes[k].frame);
      EXPECT_POSE_NEAR(loaded.keyframes[k].T_w_c, keyframes[k].T_w_c, 1e-12);
      ASSERT_EQ(loaded.keyframes[k].points.size(), keyframes[k].points.size());
      EXPECT_EQ(loaded.keyframes[k].points.back().descriptor,
                keyframes[k].points.back().descriptor);
    }
    const std::vector<MapPoint> map = system.map();
    ASSERT_EQ(loaded.landmarks.size(), map.size());
    ASSERT_FALSE(map.empty());
    EXPECT_EQ(loaded.landmarks.front().id, map.front().id);
    EXPECT_EQ(loaded.landmarks.back().p_w, map.back().p_w);
  }
}

// Old keyframes keep only the points whose landmark is in the map (System::kRecordPruneAge): the
// others have no position a run in the saved map could use, and were 58 % of the memory the
// records took on rover_loop.
TEST(SystemMap, OldKeyframesKeepOnlyMappedPoints) {
  const sim::SyntheticSequence seq = RoverLoop(150);
  for (const char* estimator : {"ba", "ekf"}) {
    const std::unique_ptr<System> owned = TrackAll(seq, estimator);
    const System& system = *owned;
    const std::vector<SavedKeyframe> keyframes = system.keyframes();
    ASSERT_GT(keyframes.size(), System::kRecordPruneAge + 8) << estimator;
    std::set<int64_t> mapped;
    for (const MapPoint& p : system.map()) mapped.insert(p.id.value);
    const size_t old_end = keyframes.size() - System::kRecordPruneAge;
    size_t unmapped_recent = 0;
    for (size_t k = 0; k < keyframes.size(); ++k) {
      size_t unmapped = 0;
      for (const SavedKeyframePoint& p : keyframes[k].points) {
        unmapped += mapped.count(p.landmark.value) == 0;
      }
      if (k < old_end) {
        // The BA's map keeps every landmark it made; the EKF evicts landmarks later (their
        // points, kept when pruned, are then unmapped again), so only the BA's count is exact.
        if (std::string(estimator) == "ba") {
          EXPECT_EQ(unmapped, 0u) << estimator << " keyframe " << keyframes[k].frame;
        }
        EXPECT_GT(keyframes[k].points.size(), 30u) << estimator << " keyframe " << keyframes[k].frame;
      } else {
        unmapped_recent += unmapped;
      }
    }
    // The recent keyframes are left whole: their tracks may still enter the map.
    EXPECT_GT(unmapped_recent, 0u) << estimator;
  }
}

}  // namespace
}  // namespace dala
