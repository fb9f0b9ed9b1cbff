#include "core/sim/recorded_path.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/sim/synthetic_sequence.h"
#include "core/sim/world.h"
#include "tests/test_util.h"

namespace dala::sim {
namespace {

// KITTI's convention: the world is the first camera (x right, y down, z forward).
// A car driving forward (+z) at `speed` m/s for `n` poses at 10 Hz, heading turning by
// `yaw_rate` rad/s about the down axis, its height (along -y) h(s) at travel s.
std::vector<StampedPose> KittiLikeDrive(int n, double speed, double yaw_rate,
                                        const std::function<double(double)>& height) {
  std::vector<StampedPose> path;
  Eigen::Vector2d xz(0, 0);  // Ground position (x, z) in the first camera's frame.
  double yaw = 0.0, s = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
    path.push_back({static_cast<int64_t>(i) * 100000000,
                    MakePose(R, Eigen::Vector3d(xz.x(), -height(s), xz.y()))});
    const Eigen::Vector3d forward = R.col(2);
    xz += 0.1 * speed * Eigen::Vector2d(forward.x(), forward.z());
    s += 0.1 * speed;
    yaw += 0.1 * yaw_rate;
  }
  return path;
}

double Flat(double) { return 0.0; }

TEST(RecordedPathTest, KittiFramePlacedWithZUpAndTheFirstHeadingAlongX) {
  const std::vector<StampedPose> placed = PlaceOnStreet(KittiLikeDrive(50, 10.0, 0.0, Flat), 1.65);
  ASSERT_EQ(placed.size(), 50u);
  for (size_t i = 0; i < placed.size(); ++i) {
    const Pose& T = placed[i].T_w_c;
    EXPECT_EQ(placed[i].t_ns, static_cast<int64_t>(i) * 100000000);
    // Camera z (forward) along the street's x, camera y (down) along -z, height 1.65 m.
    EXPECT_NEAR((T.linear().col(2) - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-12);
    EXPECT_NEAR((T.linear().col(1) + Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);
    EXPECT_NEAR(T.translation().x(), 1.0 * static_cast<double>(i), 1e-9);
    EXPECT_NEAR(T.translation().y(), 0.0, 1e-9);
    EXPECT_NEAR(T.translation().z(), 1.65, 1e-12);
  }
}

TEST(RecordedPathTest, TheShapeOfATurnIsKept) {
  // A quarter turn per 15 s at 10 m/s: distances between poses are kept exactly.
  const std::vector<StampedPose> path = KittiLikeDrive(150, 10.0, M_PI / 30, Flat);
  const std::vector<StampedPose> placed = PlaceOnStreet(path, 1.65);
  for (size_t i = 1; i < path.size(); i += 7) {
    const Pose rel = path[i - 1].T_w_c.inverse() * path[i].T_w_c;
    const Pose rel_placed = placed[i - 1].T_w_c.inverse() * placed[i].T_w_c;
    EXPECT_POSE_NEAR(rel, rel_placed, 1e-9);
  }
}

TEST(RecordedPathTest, SlowClimbsAreLevelledBumpsKept) {
  // 10 m of climb over 500 m, plus a 5 cm bump of 2 m at 250 m.
  const auto height = [](double s) { return 0.02 * s + (std::abs(s - 250.0) < 1.0 ? 0.05 : 0.0); };
  const std::vector<StampedPose> placed =
      PlaceOnStreet(KittiLikeDrive(500, 10.0, 0.0, height), 1.5);
  double max_off = 0.0;
  for (size_t i = 30; i + 30 < placed.size(); ++i) {
    const double s = static_cast<double>(i);
    if (std::abs(s - 250.0) > 30.0) {
      max_off = std::max(max_off, std::abs(placed[i].T_w_c.translation().z() - 1.5));
    }
  }
  EXPECT_LT(max_off, 1e-6);  // A constant slope averages out exactly in the window.
  EXPECT_NEAR(placed[250].T_w_c.translation().z() - 1.5, 0.05, 0.01);
}

TEST(RecordedPathTest, PathsThatCannotBeDrivenOnAStreetAreRefused) {
  EXPECT_THROW(PlaceOnStreet(KittiLikeDrive(1, 10.0, 0.0, Flat), 1.65), Error);
  EXPECT_THROW(PlaceOnStreet(KittiLikeDrive(10, 10.0, 0.0, Flat), 0.0), Error);
  std::vector<StampedPose> backwards = KittiLikeDrive(10, 10.0, 0.0, Flat);
  backwards[5].t_ns = backwards[4].t_ns;
  EXPECT_THROW(PlaceOnStreet(backwards, 1.65), Error);
  // A camera that looks every way (its down axis turning through a full circle).
  std::vector<StampedPose> tumbling;
  for (int i = 0; i < 12; ++i) {
    const double roll = 2 * M_PI * i / 12;
    tumbling.push_back(
        {static_cast<int64_t>(i) * 100000000,
         MakePose(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                  Eigen::Vector3d(0, 0, i))});
  }
  try {
    PlaceOnStreet(tumbling, 1.65);
    ADD_FAILURE() << "a tumbling camera was placed on a street";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("down direction"), std::string::npos) << e.what();
  }
}

TEST(RecordedPathTest, InterpolatesBetweenPosesAndHoldsTheEnds) {
  const std::vector<StampedPose> placed = PlaceOnStreet(KittiLikeDrive(20, 8.0, 0.3, Flat), 1.65);
  const RecordedPath path(placed);
  EXPECT_NEAR(path.duration_s(), 1.9, 1e-12);
  for (size_t i = 0; i < placed.size(); ++i) {
    EXPECT_POSE_NEAR(path.T_w_c(0.1 * static_cast<double>(i)), placed[i].T_w_c, 1e-9);
  }
  EXPECT_POSE_NEAR(path.T_w_c(0.35), InterpolatePose(placed[3].T_w_c, placed[4].T_w_c, 0.5), 1e-9);
  EXPECT_POSE_NEAR(path.T_w_c(-1.0), placed.front().T_w_c, 1e-12);
  EXPECT_POSE_NEAR(path.T_w_c(5.0), placed.back().T_w_c, 1e-12);
}

// Distance from q to the segment [a, b] on the ground.
double DistanceToSegment(const Eigen::Vector2d& q, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double t = d.squaredNorm() > 0 ? std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0;
  return (q - (a + t * d)).norm();
}

// The walls (vertical quads) of a world and their nearest distance to the path's ground track.
struct Walls {
  int count = 0;
  double nearest_m = 1e9;
};
Walls WallsAlong(const World& world, const std::vector<StampedPose>& placed) {
  Walls w;
  for (const Surface& s : world.scene.surfaces) {
    const Eigen::Vector3d& vertical = std::abs(s.a_w.z()) > 0 ? s.a_w : s.b_w;
    const Eigen::Vector3d& horizontal = std::abs(s.a_w.z()) > 0 ? s.b_w : s.a_w;
    if (s.triangle || std::abs(vertical.z()) == 0 || std::abs(horizontal.z()) > 0) continue;
    double nearest = 1e9;
    for (const StampedPose& p : placed) {
      nearest =
          std::min(nearest, DistanceToSegment(p.T_w_c.translation().head<2>(), s.o_w.head<2>(),
                                              (s.o_w + horizontal).head<2>()));
    }
    w.nearest_m = std::min(w.nearest_m, nearest);
    w.count += nearest < 30.0 ? 1 : 0;  // The street's, not the skyline's.
  }
  return w;
}

TEST(RecordedPathTest, StreetsLinedClearOfThePathAndLinedOnceWhenDrivenTwice) {
  // 150 m east, then back along the same street (a U-turn in place: heading reversed).
  std::vector<StampedPose> out = KittiLikeDrive(150, 10.0, 0.0, Flat);
  std::vector<StampedPose> out_and_back = out;
  const Pose turn = MakePose(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix(),
                             Eigen::Vector3d::Zero());
  for (int i = 149; i >= 0; --i) {
    out_and_back.push_back({out_and_back.back().t_ns + 100000000, out[i].T_w_c * turn});
  }
  const std::vector<StampedPose> once = PlaceOnStreet(out, 1.65);
  const std::vector<StampedPose> twice = PlaceOnStreet(out_and_back, 1.65);
  const Walls w_once = WallsAlong(BuildWorldAlongPath(once, 3, 64), once);
  const Walls w_twice = WallsAlong(BuildWorldAlongPath(twice, 3, 64), twice);
  // Buildings stand back from the street's centre (half width 6 m; crates from 3.5 m).
  EXPECT_GT(w_once.nearest_m, 3.0);
  EXPECT_GT(w_twice.nearest_m, 3.0);
  // Both sides of 150 m of street: a few dozen boxes (144 walls). Driven back, the gaps left
  // the first time fill (192); lining each pass on its own would give 1.8x.
  EXPECT_GT(w_once.count, 100);
  EXPECT_LT(w_twice.count, 1.5 * w_once.count) << w_once.count << " walls one way";
}

TEST(RecordedPathTest, SyntheticSequenceDrivesThePathAtItsPoses) {
  SimOptions o;
  o.path = KittiLikeDrive(40, 10.0, 0.2, Flat);
  o.texture_size = 64;
  o.stereo = false;
  o.width = 320;
  o.height = 120;
  o.fx = o.fy = 180;
  const SyntheticSequence seq(o);
  ASSERT_EQ(seq.size(), 40u);  // Every pose of 3.9 s at 10 fps.
  const std::vector<StampedPose> placed = PlaceOnStreet(o.path, o.path_camera_height);
  for (size_t i = 0; i < seq.size(); i += 13)
    EXPECT_POSE_NEAR(seq.T_w_c0(i), placed[i].T_w_c, 1e-9);
  // The street is open ahead: the image centre sees something beyond 10 m (or the sky).
  cv::Mat depth;
  seq.RenderView(seq.T_w_c0(0), &depth);
  const float z = depth.at<float>(o.height / 2, o.width / 2);
  EXPECT_TRUE(z == 0.f || z > 10.f) << z;
}

}  // namespace
}  // namespace dala::sim
