#include "frontend/keyframe_policy.h"

#include <gtest/gtest.h>

#include <string>

namespace dala {
namespace {

KeyframeEvidence Still(int frames_since_keyframe) {
  KeyframeEvidence e;
  e.frames_since_keyframe = frames_since_keyframe;
  e.tracked_fraction = 0.95;
  e.median_parallax_px = 0.2;  // Image noise.
  return e;
}

TEST(KeyframePolicy, EachCriterionNamesItself) {
  const KeyframePolicy policy{KeyframePolicyOptions()};
  const char* reason = nullptr;
  KeyframeEvidence e = Still(2);
  EXPECT_FALSE(policy.IsKeyframe(e, &reason));
  e.tracked_fraction = 0.5;
  ASSERT_TRUE(policy.IsKeyframe(e, &reason));
  EXPECT_EQ(std::string(reason), "tracked fraction");
  e = Still(2);
  e.median_parallax_px = 31;
  ASSERT_TRUE(policy.IsKeyframe(e, &reason));
  EXPECT_EQ(std::string(reason), "parallax");
  // Distance in stereo baselines (0.5 by default): 0.25 m is past 0.5 x 0.4 m, not 0.5 x 0.54 m.
  e = Still(2);
  e.T_kf_cur.translation().z() = 0.25;
  e.stereo_baseline_m = 0.4;
  ASSERT_TRUE(policy.IsKeyframe(e, &reason));
  EXPECT_EQ(std::string(reason), "distance");
  e.stereo_baseline_m = 0.54;
  EXPECT_FALSE(policy.IsKeyframe(e));
  // Revisiting a held place: 2.5 baselines (1 m on the 0.4 m rig).
  e.stereo_baseline_m = 0.4;
  e.revisiting = true;
  EXPECT_FALSE(policy.IsKeyframe(e));
  e.T_kf_cur.translation().z() = 1.2;
  ASSERT_TRUE(policy.IsKeyframe(e, &reason));
  EXPECT_EQ(std::string(reason), "distance");
  e.revisiting = false;
  e.stereo_baseline_m = 0.0;  // One camera: no distance unit, no distance criterion.
  e.T_kf_cur.translation().z() = 100;
  EXPECT_FALSE(policy.IsKeyframe(e));
  // The optional metric cap (off by default).
  KeyframePolicyOptions metres;
  metres.max_distance_m = 1.0;
  e.T_kf_cur.translation().z() = 1.5;
  ASSERT_TRUE(KeyframePolicy(metres).IsKeyframe(e, &reason));
  EXPECT_EQ(std::string(reason), "distance");
  KeyframePolicyOptions none;
  none.max_distance_baselines = 0;  // Off: a distance alone makes no keyframe.
  e.stereo_baseline_m = 0.4;
  e.T_kf_cur.translation().z() = 100;
  EXPECT_FALSE(KeyframePolicy(none).IsKeyframe(e));
  e = Still(2);
  e.T_kf_cur.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  ASSERT_TRUE(policy.IsKeyframe(e, &reason));
  EXPECT_EQ(std::string(reason), "rotation");
}

// The frame count makes a keyframe only when the view changed at all: a still camera keeps its
// keyframe however long it stays (bounded map and memory), a slowly moving one still gets one
// every max_frames frames.
TEST(KeyframePolicy, FrameCountNeedsTheViewToHaveChanged) {
  const KeyframePolicy policy{KeyframePolicyOptions()};
  EXPECT_FALSE(policy.IsKeyframe(Still(10)));
  EXPECT_FALSE(policy.IsKeyframe(Still(100000)));
  KeyframeEvidence slow = Still(10);
  slow.median_parallax_px = 1.5;
  const char* reason = nullptr;
  ASSERT_TRUE(policy.IsKeyframe(slow, &reason));
  EXPECT_EQ(std::string(reason), "frame count");
  KeyframeEvidence turning = Still(10);
  turning.T_kf_cur.linear() =
      Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()).toRotationMatrix();  // > 0.017 rad.
  EXPECT_TRUE(policy.IsKeyframe(turning));
  EXPECT_FALSE(policy.IsKeyframe(Still(9)));
}

TEST(KeyframePolicy, InvalidOptionsAreRejected) {
  KeyframePolicyOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why));
  o.min_parallax_px = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("min_parallax_px"), std::string::npos);
  o = KeyframePolicyOptions();
  o.max_distance_m = 0;
  EXPECT_TRUE(o.IsValid(&why));
  o.max_distance_m = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_distance_m"), std::string::npos);
  o = KeyframePolicyOptions();
  o.revisit_distance_baselines = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("revisit_distance_baselines"), std::string::npos);
  o = KeyframePolicyOptions();
  o.max_distance_baselines = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_distance_baselines"), std::string::npos);
}

}  // namespace
}  // namespace dala
