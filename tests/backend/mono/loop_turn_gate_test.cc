// The loop gate on the turn a loop would make (core/loop_turn.h, which the stereo rig's place
// recognition shares) and one camera's keyframe path (backend/mono/loop_turn_gate.h).
#include "backend/mono/loop_turn_gate.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace dala {
namespace {

Pose Turned(const Pose& T, double deg, const Eigen::Vector3d& axis) {
  Pose out = T;
  out.linear() = T.rotation() * Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).matrix();
  return out;
}

Pose At(double x, double y, double z) {
  Pose T = Pose::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

TEST(LoopTurnGate, MeasuresTheTurnAboutAnyAxisAndNotTheMove) {
  const Pose T_w_c = Turned(At(1, 2, 3), 40.0, Eigen::Vector3d(0.3, -1, 0.2));
  // The loop moves the camera by 20 m and turns it by 7 deg about another axis.
  Pose T_loop = Turned(T_w_c, 7.0, Eigen::Vector3d(1, 0.5, -0.4));
  T_loop.translation() += Eigen::Vector3d(20, 0, 0);
  const LoopTurn t = CheckLoopTurn(T_w_c.rotation(), T_loop.rotation(), /*path=*/0.0, 10.0, 0.01);
  EXPECT_NEAR(t.turn_deg, 7.0, 1e-9);
  EXPECT_DOUBLE_EQ(t.max_deg, 10.0);
  EXPECT_TRUE(t.within);
}

TEST(LoopTurnGate, RefusesALookAlikePlaceSeenFromAnotherStreet) {
  // Rendered KITTI 00 (docs/monocular.md, "Loop closure"): a false loop turned the camera by
  // 93 deg after 609 map units of path; the gate there is 10 + 0.01 x 609 = 16.1 deg.
  const Pose T_w_c = At(5, 0, 7);
  const LoopTurn t =
      CheckLoopTurn(T_w_c.rotation(), Turned(T_w_c, 93.0, Eigen::Vector3d::UnitY()).rotation(),
                    609.0, 10.0, 0.01);
  EXPECT_NEAR(t.max_deg, 16.09, 1e-9);
  EXPECT_FALSE(t.within);
}

TEST(LoopTurnGate, WidensWithThePathSinceTheOldKeyframe) {
  const Pose T_w_c = At(0, 0, 0);
  const Pose T_loop = Turned(T_w_c, 30.0, Eigen::Vector3d::UnitY());
  const Eigen::Matrix3d R = T_w_c.rotation(), R_loop = T_loop.rotation();
  EXPECT_FALSE(CheckLoopTurn(R, R_loop, 1000.0, 10.0, 0.01).within);  // 20 deg.
  EXPECT_TRUE(CheckLoopTurn(R, R_loop, 2500.0, 10.0, 0.01).within);   // 35 deg.
}

TEST(LoopTurnGate, PathRunsFromTheOldKeyframeThroughTheLaterOnesToTheCamera) {
  std::map<KeyframeId, Pose> T_w_kf;
  T_w_kf[KeyframeId(0)] = At(-100, 0, 0);  // Before the old keyframe: not counted.
  T_w_kf[KeyframeId(3)] = At(0, 0, 0);
  T_w_kf[KeyframeId(4)] = At(3, 4, 0);  // 5 from keyframe 3.
  T_w_kf[KeyframeId(7)] = At(3, 4, 2);  // 2 more.
  EXPECT_DOUBLE_EQ(KeyframePathFrom(T_w_kf, KeyframeId(3), Eigen::Vector3d(3, 4, 12)), 17.0);
  EXPECT_DOUBLE_EQ(KeyframePathFrom(T_w_kf, KeyframeId(7), Eigen::Vector3d(3, 4, 2)), 0.0);
  EXPECT_DOUBLE_EQ(KeyframePathFrom(T_w_kf, KeyframeId(5), Eigen::Vector3d::Zero()), 0.0);
}

}  // namespace
}  // namespace dala
