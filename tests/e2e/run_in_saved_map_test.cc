// System::UseMap (`dala run --map FILE`): a second run starts in the map an earlier run saved,
// relocalises in it and continues in its frame. Rendered rover stretch with exact ground truth:
// run A maps frames 0-149 (noisy images) and saves its map; run B starts at frame 60 with
// clean images of the same poses (other pixels, the same places), so B's poses must come out
// in A's world frame (A's first camera) and unit, which B could not know without the map.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include "backend/system.h"
#include "core/error.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;

sim::SyntheticSequence RoverStretch() {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 150;
  sim.seed = 1;
  return sim::SyntheticSequence(sim);
}

SystemOptions BaOptions(const char* mode) {
  SystemOptions options;
  options.estimator = "ba";
  options.mode = mode;
  return options;
}

// Run A over every frame; its map, saved and read back.
SavedMap MapOfRunA(const sim::SyntheticSequence& seq, const SystemOptions& options,
                   Trajectory* trajectory) {
  System a(seq.rig(), options);
  for (size_t i = 0; i < seq.size(); ++i) a.Track(seq.Render(i));
  *trajectory = a.trajectory();
  testing::TempDir dir;
  a.SaveMap(dir / "a.dmap");
  return System::LoadMap(dir / "a.dmap");
}

struct RunB {
  std::map<int64_t, Pose> pose_at;  // By time.
  int first_valid = -1;              // Frame index of the first pose.
  int lost_after = 0;
  std::string first_note;
};

// Run B in A's map: frames 60-149 re-rendered without noise (both cameras in stereo), from
// A's camera poses moved by `T_c_b` (B's camera in A's camera).
RunB RunInMap(const sim::SyntheticSequence& seq, const SystemOptions& options, const SavedMap& map,
              const Pose& T_c_b = Pose::Identity()) {
  System b(seq.rig(), options);
  b.UseMap(map);
  RunB out;
  for (size_t i = 60; i < seq.size(); ++i) {
    Frame f = seq.Render(i);
    f.left = seq.RenderView(seq.T_w_c0(i) * T_c_b);
    if (!f.right.empty()) f.right = seq.RenderView(seq.T_w_c0(i) * T_c_b * seq.T_c0_c1());
    const TrackResult r = b.Track(f);
    if (r.valid && out.first_valid < 0) {
      out.first_valid = static_cast<int>(i);
      out.first_note = b.stats().back().note;
    }
    if (out.first_valid >= 0 && !r.valid) ++out.lost_after;
  }
  for (const StampedPose& p : b.trajectory().poses) out.pose_at[p.t_ns] = p.T_w_c;
  return out;
}

// Bounds: 1.5x the best values recorded (runs are bit-identical). Without the map B would start
// at the identity, 15 m and more from where A's frame puts frame 60.
constexpr double kStereoMapErrorMetresBest = 0.00779;  // 0.5 m aside, 3 deg.
constexpr double kMonoMapOffsetMetresBest = 0.0217;

TEST(RunInSavedMap, StereoRunContinuesInTheSavedMapsFrame) {
  const sim::SyntheticSequence seq = RoverStretch();
  Trajectory a;
  const SavedMap map = MapOfRunA(seq, BaOptions("stereo"), &a);
  ASSERT_TRUE(map.metric);
  // B drives 0.5 m to the left of A's path, turned by 3 degrees: other viewpoints of the same
  // places.
  Pose T_c_b = Pose::Identity();
  T_c_b.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_c_b.translation() = Eigen::Vector3d(-0.5, 0.0, 0.0);
  const RunB b = RunInMap(seq, BaOptions("stereo"), map, T_c_b);
  EXPECT_EQ(b.first_valid, 60) << "the first frame is in the map";
  EXPECT_EQ(b.first_note, "localised in the saved map");
  EXPECT_EQ(b.lost_after, 0);
  ASSERT_EQ(b.pose_at.size(), 90u);
  // A's world frame is A's first camera: the ground truth there, no alignment.
  const Pose T_a_w = seq.T_w_c0(0).inverse();
  double sum = 0.0;
  for (size_t i = 60; i < seq.size(); ++i) {
    const Pose T_gt = T_a_w * seq.T_w_c0(i) * T_c_b;
    sum += (b.pose_at.at(seq.t_ns(i)).translation() - T_gt.translation()).norm();
  }
  const double mean = sum / 90.0;
  std::cout << "[ measured ] ba/stereo run B (frames 60-149, 0.5 m aside, 3 deg) in run A's "
               "saved map: mean position error "
            << mean << " m in A's frame, unaligned" << std::endl;
  testing::ExpectWithinBound("ba/stereo run B (0.5 m aside, 3 deg) in A's map, unaligned mean error",
                             mean, kStereoMapErrorMetresBest, "m");
}

// One camera: A's map has A's arbitrary unit; B continues in it, so B's poses are A's poses of
// the same frames (compared in metres through A's scale to the ground truth, frames 10-60).
TEST(RunInSavedMap, MonoRunContinuesInTheSavedMapsFrameAndUnit) {
  const sim::SyntheticSequence seq = RoverStretch();
  Trajectory a;
  const SavedMap map = MapOfRunA(seq, BaOptions("mono"), &a);
  ASSERT_FALSE(map.metric);
  std::map<int64_t, Eigen::Vector3d> a_at;
  for (const StampedPose& p : a.poses) a_at[p.t_ns] = p.T_w_c.translation();
  const double scale = (a_at.at(seq.t_ns(60)) - a_at.at(seq.t_ns(10))).norm() /
                       (seq.T_w_c0(60).translation() - seq.T_w_c0(10).translation()).norm();
  const RunB b = RunInMap(seq, BaOptions("mono"), map);
  EXPECT_EQ(b.first_valid, 60);
  EXPECT_EQ(b.lost_after, 0);
  ASSERT_EQ(b.pose_at.size(), 90u);
  double sum = 0.0;
  for (size_t i = 60; i < seq.size(); ++i) {
    sum += (b.pose_at.at(seq.t_ns(i)).translation() - a_at.at(seq.t_ns(i))).norm();
  }
  const double mean = sum / 90.0 / scale;
  std::cout << "[ measured ] ba/mono run B (frames 60-149) in run A's saved map: mean distance "
               "to A's poses "
            << mean << " m" << std::endl;
  testing::ExpectWithinBound("ba/mono run B in A's map, mean distance to A's poses", mean,
                             kMonoMapOffsetMetresBest, "m");
}

// A map that does not suit the run is refused before any frame, saying why.
TEST(RunInSavedMap, UnsuitableMapsAreRefusedWithTheReason) {
  const sim::SyntheticSequence seq = RoverStretch();
  SavedMap map;
  map.descriptor_size = 121;
  map.thumbnail_width = 16;
  map.thumbnail_height = 10;
  SavedKeyframe kf;
  kf.thumbnail.assign(160, 0.f);
  map.keyframes.push_back(kf);
  map.landmarks.push_back({LandmarkId(3), Eigen::Vector3d(0, 0, 5), 2});
  const auto error_of = [&](const SavedMap& m, const SystemOptions& options) -> std::string {
    try {
      System(seq.rig(), options).UseMap(m);
    } catch (const Error& e) {
      return e.message();
    }
    return "no error";
  };
  SavedMap one_camera = map;
  one_camera.metric = false;
  EXPECT_THAT(error_of(one_camera, BaOptions("stereo")), HasSubstr("--mode mono"));
  SavedMap other_descriptors = map;
  other_descriptors.descriptor_size = 49;
  EXPECT_THAT(error_of(other_descriptors, BaOptions("stereo")), HasSubstr("harris.patch_size"));
  SavedMap other_thumbnails = map;
  other_thumbnails.thumbnail_width = 32;
  EXPECT_THAT(error_of(other_thumbnails, BaOptions("stereo")), HasSubstr("thumbnail"));
  SavedMap nan_landmark = map;
  nan_landmark.landmarks[0].p_w.x() = std::nan("");
  EXPECT_THAT(error_of(nan_landmark, BaOptions("stereo")), HasSubstr("non-finite"));
  EXPECT_THAT(error_of(SavedMap(), BaOptions("stereo")), HasSubstr("no keyframes"));
  SystemOptions ekf;
  ekf.estimator = "ekf";
  EXPECT_THAT(error_of(map, ekf), HasSubstr("--estimator ba"));
  SystemOptions no_loop = BaOptions("stereo");
  no_loop.frontend.loop.relocalise = false;
  EXPECT_THAT(error_of(map, no_loop), HasSubstr("loop.relocalise=1"));
  SystemOptions no_search = BaOptions("stereo");
  no_search.frontend.local_map.enable = false;
  EXPECT_THAT(error_of(map, no_search), HasSubstr("frontend.local_map_search=1"));
  // Points the matcher would index with: a crafted file can carry any value (with a valid
  // checksum), so each is checked before the place recognition sees it.
  SavedKeyframePoint good;
  good.landmark = LandmarkId(3);
  good.uv = Eigen::Vector2d(100, 100);
  good.lambda1 = 900;
  good.lambda2 = 300;
  good.descriptor.assign(121, static_cast<int8_t>(13));
  SavedMap with_point = map;
  with_point.keyframes[0].points.push_back(good);
  EXPECT_EQ(error_of(with_point, BaOptions("stereo")), "no error");
  const auto bad_point = [&](const std::function<void(SavedKeyframePoint*)>& spoil) {
    SavedMap m = with_point;
    spoil(&m.keyframes[0].points[0]);
    return error_of(m, BaOptions("stereo"));
  };
  for (const auto& spoil : std::vector<std::function<void(SavedKeyframePoint*)>>{
           [](SavedKeyframePoint* p) { p->uv.x() = std::nan(""); },
           [](SavedKeyframePoint* p) { p->uv.y() = 1e12; },
           [](SavedKeyframePoint* p) { p->orientation = std::nanf(""); },
           [](SavedKeyframePoint* p) { p->scale = 0.f; },
           [](SavedKeyframePoint* p) { p->scale = 1e30f; },
           [](SavedKeyframePoint* p) { p->lambda2 = -1.f; },
           [](SavedKeyframePoint* p) { p->descriptor.pop_back(); },
           [](SavedKeyframePoint* p) { p->landmark = LandmarkId(std::numeric_limits<int64_t>::max()); }}) {
    EXPECT_THAT(bad_point(spoil), HasSubstr("out of range"));
  }
  SavedMap bad_thumbnail = with_point;
  bad_thumbnail.keyframes[0].thumbnail.pop_back();
  EXPECT_THAT(error_of(bad_thumbnail, BaOptions("stereo")), HasSubstr("thumbnail"));
  System twice(seq.rig(), BaOptions("stereo"));
  twice.UseMap(with_point);
  EXPECT_THROW(twice.UseMap(with_point), Error);
}

}  // namespace
}  // namespace dala
