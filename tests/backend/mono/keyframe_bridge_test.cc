// The pose of a frame from the two-view geometry with the last keyframe
// (backend/mono/keyframe_bridge.h), on exact synthetic correspondences with pixel noise.

#include "backend/mono/keyframe_bridge.h"

#include <gtest/gtest.h>

#include "tests/backend/mono/two_view_scene.h"

namespace dala {
namespace {

PinholeCamera Camera() { return testing::EurocGeometryCamera(); }

struct Scene {
  std::map<LandmarkId, BaObservation> keyframe;
  FrameMeasurement current;
};

// Points 4-12 m in front of the keyframe, seen from it and from T_w_cur, with 0.5 px noise
// (ids: the points' indices).
Scene Render(const Pose& T_w_kf, const Pose& T_w_cur, int n = 300) {
  const testing::TwoViews views =
      testing::RenderTwoViews(Camera(), T_w_cur.inverse() * T_w_kf, false, 0.5, 3, n);
  Scene scene;
  for (size_t i = 0; i < views.ref.size(); ++i) {
    BaObservation b;
    b.landmark = LandmarkId(static_cast<int64_t>(i));
    b.uv = views.ref[i];
    scene.keyframe[b.landmark] = b;
    FeatureObservation o;
    o.landmark = b.landmark;
    o.uv = views.cur[i];
    scene.current.observations.push_back(o);
  }
  return scene;
}

TEST(KeyframeBridge, PlacesTheFrameWithTheGivenStepLength) {
  const Pose T_w_kf = MakePose(ExpSO3(Eigen::Vector3d(0.1, -0.3, 0.05)), Eigen::Vector3d(4, 1, 2));
  const Pose T_kf_cur =
      MakePose(ExpSO3(Eigen::Vector3d(0.01, 0.06, -0.02)), Eigen::Vector3d(0.3, -0.05, 0.6));
  const Pose T_w_cur = T_w_kf * T_kf_cur;
  const Scene scene = Render(T_w_kf, T_w_cur);
  std::string why;
  const std::optional<KeyframeBridge> bridge =
      BridgeFromKeyframe(Camera(), T_w_kf, scene.keyframe, scene.current,
                         T_kf_cur.translation().norm(), TwoViewOptions(), &why);
  ASSERT_TRUE(bridge.has_value()) << why;
  EXPECT_GT(bridge->num_points, 200);
  // The step's direction and the rotation from the images; its length as given.
  EXPECT_LT((bridge->T_w_cur.translation() - T_w_cur.translation()).norm(),
            0.02 * T_kf_cur.translation().norm());
  EXPECT_LT(LogSO3(bridge->T_w_cur.linear().transpose() * T_w_cur.linear()).norm(), 0.002);
  // Twice the length: the same direction, twice as far from the keyframe.
  const std::optional<KeyframeBridge> doubled =
      BridgeFromKeyframe(Camera(), T_w_kf, scene.keyframe, scene.current,
                         2 * T_kf_cur.translation().norm(), TwoViewOptions(), &why);
  ASSERT_TRUE(doubled.has_value()) << why;
  const Eigen::Vector3d step = doubled->T_w_cur.translation() - T_w_kf.translation();
  EXPECT_NEAR(step.norm(), 2 * T_kf_cur.translation().norm(), 1e-9);
}

TEST(KeyframeBridge, RefusesAPairWithoutParallaxAndAStepWithoutLength) {
  const Pose T_w_kf = Pose::Identity();
  // A pure rotation: no translation to take a direction from.
  const Pose rotated = MakePose(ExpSO3(Eigen::Vector3d(0.0, 0.08, 0.0)), Eigen::Vector3d::Zero());
  const Scene turn = Render(T_w_kf, rotated);
  std::string why;
  EXPECT_FALSE(
      BridgeFromKeyframe(Camera(), T_w_kf, turn.keyframe, turn.current, 1.0, TwoViewOptions(), &why)
          .has_value());
  EXPECT_NE(why.find("parallax"), std::string::npos) << why;
  const Scene moved =
      Render(T_w_kf, MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.5, 0, 0)));
  EXPECT_FALSE(BridgeFromKeyframe(Camera(), T_w_kf, moved.keyframe, moved.current, 0.0,
                                  TwoViewOptions(), &why)
                   .has_value());
  EXPECT_EQ(why, "no speed to scale the step by");
}

}  // namespace
}  // namespace dala
