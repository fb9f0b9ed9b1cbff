// System::UseMap (`dala run --map FILE`): a second run starts in the map an earlier run saved,
// relocalises in it and continues in its frame. Rendered rover stretch with exact ground truth:
// run A maps frames 0-149 (noisy images) and saves its map; run B starts at frame 60 with
// clean images of the same poses (other pixels, the same places), so B's poses must come out
// in A's world frame (A's first camera) and unit, which B could not know without the map.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

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

// Run B in A's map: frames 60-149 re-rendered without noise (both cameras in stereo).
RunB RunInMap(const sim::SyntheticSequence& seq, const SystemOptions& options,
              const SavedMap& map) {
  System b(seq.rig(), options);
  b.UseMap(map);
  RunB out;
  for (size_t i = 60; i < seq.size(); ++i) {
    Frame f = seq.Render(i);
    f.left = seq.RenderView(seq.T_w_c0(i));
    if (!f.right.empty()) f.right = seq.RenderView(seq.T_w_c0(i) * seq.T_c0_c1());
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

// Bounds at 1.5x the measured values (runs are bit-identical). Without the map B would start at
// the identity, 15 m and more from where A's frame puts frame 60.
constexpr double kStereoMapErrorMetres = 0.036;  // measured 0.0240 m.
constexpr double kMonoMapOffsetMetres = 0.052;   // measured 0.0350 m.

TEST(RunInSavedMap, StereoRunContinuesInTheSavedMapsFrame) {
  const sim::SyntheticSequence seq = RoverStretch();
  Trajectory a;
  const SavedMap map = MapOfRunA(seq, BaOptions("stereo"), &a);
  ASSERT_TRUE(map.metric);
  const RunB b = RunInMap(seq, BaOptions("stereo"), map);
  EXPECT_EQ(b.first_valid, 60) << "the first frame is in the map";
  EXPECT_EQ(b.first_note, "localised in the saved map");
  EXPECT_EQ(b.lost_after, 0);
  ASSERT_EQ(b.pose_at.size(), 90u);
  // A's world frame is A's first camera: the ground truth there, no alignment.
  const Pose T_a_w = seq.T_w_c0(0).inverse();
  double sum = 0.0;
  for (size_t i = 60; i < seq.size(); ++i) {
    const Pose T_gt = T_a_w * seq.T_w_c0(i);
    sum += (b.pose_at.at(seq.t_ns(i)).translation() - T_gt.translation()).norm();
  }
  const double mean = sum / 90.0;
  std::cout << "[ measured ] ba/stereo run B (frames 60-149) in run A's saved map: mean "
               "position error "
            << mean << " m in A's frame, unaligned" << std::endl;
  EXPECT_LT(mean, kStereoMapErrorMetres);
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
  EXPECT_LT(mean, kMonoMapOffsetMetres);
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
}

}  // namespace
}  // namespace dala
