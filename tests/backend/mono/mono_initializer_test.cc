// MonoInitializer's choice of reference frame: when the reference's tracks are gone, the oldest
// frame since then that shares a reference's worth of tracks with the current one is tried as
// its reference, and kept if the pair initialises at once; the frames of the references given
// up are handed over with the initialisation. With the next-frame check, a pair waits for the
// next frame, which keeps it or drops it.

#include "backend/mono/mono_initializer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "tests/backend/mono/two_view_scene.h"

namespace dala {
namespace {

using testing::KittiGeometryCamera;

// Points 4-15 m in front of the first camera; frame f observes the points of `ids`, from the
// camera at z_m along the optical axis (noise-free pixels).
class ForwardDrive {
 public:
  ForwardDrive() {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, cam_.width - 1), v(0, cam_.height - 1), z(4, 15);
    for (int i = 0; i < 600; ++i) points_.push_back(cam_.Unproject({u(rng), v(rng)}) * z(rng));
  }

  FrameMeasurement Frame(int f, double z_m, const std::vector<std::pair<int, int>>& ids) const {
    FrameMeasurement m;
    m.frame = FrameId(f);
    m.t_ns = static_cast<int64_t>(f) * 100000000;
    for (const auto& [first, last] : ids) {
      for (int i = first; i < last; ++i) {
        Eigen::Vector2d uv;
        const Eigen::Vector3d p_c = points_[i] - Eigen::Vector3d(0, 0, z_m);
        if (!cam_.Project(p_c, &uv) || !cam_.InImage(uv)) continue;
        FeatureObservation o;
        o.landmark = LandmarkId(i);
        o.uv = uv;
        m.observations.push_back(o);
      }
    }
    return m;
  }

 private:
  PinholeCamera cam_ = KittiGeometryCamera();
  std::vector<Eigen::Vector3d> points_;
};

// Frames 0 and 1 of every test: frame 0 sees points 0-199; frame 1, 0.05 m on (a pair too weak
// to start from), 80 of them and 200 new. Neither initialises.
void AddTheWeakPair(const ForwardDrive& drive, MonoInitializer* init) {
  EXPECT_FALSE(init->Add(drive.Frame(0, 0.0, {{0, 200}})));
  EXPECT_FALSE(init->Add(drive.Frame(1, 0.05, {{0, 80}, {200, 400}})));
}

TEST(MonoInitializer, AFrameBetweenInitialisesWhenTheReferencesTracksAreGone) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), MonoInitializerOptions());
  AddTheWeakPair(drive, &init);
  EXPECT_NE(init.reason().find("reference frame 0"), std::string::npos) << init.reason();
  // Frame 2, 1.5 m on: 30 of frame 0's (its tracks are gone), 150 of frame 1's new ones.
  const std::optional<MonoInitialization> result =
      init.Add(drive.Frame(2, 1.5, {{50, 80}, {200, 350}, {400, 600}}));
  ASSERT_TRUE(result) << init.reason();
  EXPECT_EQ(result->reference.frame, FrameId(1));
  EXPECT_TRUE(result->between.empty());
  EXPECT_EQ(result->current.frame, FrameId(2));
  EXPECT_GE(result->p_ref.size(), 100u);  // Of the 150 tracks from frame 1.
  // The reference given up comes with it, for the estimator to place in the new map.
  ASSERT_EQ(result->earlier.size(), 1u);
  EXPECT_EQ(result->earlier[0].frame, FrameId(0));
}

TEST(MonoInitializer, FramesOfReferencesGivenUpAreHandedOverInTimeOrder) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), MonoInitializerOptions());
  AddTheWeakPair(drive, &init);
  // Frame 2 becomes the reference (frame 0's tracks are gone, frame 1 is too close to it);
  // frame 3, 1.5 m on, initialises from it.
  EXPECT_FALSE(init.Add(drive.Frame(2, 0.08, {{50, 80}, {200, 350}, {400, 600}})));
  const std::optional<MonoInitialization> result =
      init.Add(drive.Frame(3, 1.58, {{200, 350}, {400, 600}}));
  ASSERT_TRUE(result) << init.reason();
  EXPECT_EQ(result->reference.frame, FrameId(2));
  ASSERT_EQ(result->earlier.size(), 2u);
  EXPECT_EQ(result->earlier[0].frame, FrameId(0));
  EXPECT_EQ(result->earlier[1].frame, FrameId(1));
  // A new start after Reset hands over nothing from before it.
  init.Reset();
  AddTheWeakPair(drive, &init);
  const std::optional<MonoInitialization> again =
      init.Add(drive.Frame(2, 1.5, {{50, 80}, {200, 350}, {400, 600}}));
  ASSERT_TRUE(again) << init.reason();
  ASSERT_EQ(again->earlier.size(), 1u);
  EXPECT_EQ(again->earlier[0].frame, FrameId(0));
}

TEST(MonoInitializer, TheCurrentFrameIsTheNewReferenceWhenNoFrameBetweenReachesIt) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), MonoInitializerOptions());
  AddTheWeakPair(drive, &init);
  // Frame 2 keeps 30 of frame 0's points and 30 of frame 1's: no pair can be tried.
  EXPECT_FALSE(init.Add(drive.Frame(2, 1.5, {{50, 80}, {200, 230}, {400, 600}})));
  EXPECT_NE(init.reason().find("frame 2 is the new reference"), std::string::npos) << init.reason();
}

TEST(MonoInitializer, AFrameBetweenThatDoesNotInitialiseNowIsNotKept) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), MonoInitializerOptions());
  AddTheWeakPair(drive, &init);
  // Frame 2 shares 150 points with frame 1 but has moved only 0.03 m from it.
  EXPECT_FALSE(init.Add(drive.Frame(2, 0.08, {{50, 80}, {200, 350}, {400, 600}})));
  EXPECT_NE(init.reason().find("frame 1 as the reference: "), std::string::npos) << init.reason();
  EXPECT_NE(init.reason().find("frame 2 is the new reference"), std::string::npos) << init.reason();
}

// m with its points' pixels shuffled among them: each landmark seen where another one is.
FrameMeasurement Scrambled(FrameMeasurement m) {
  std::vector<Eigen::Vector2d> uv;
  for (const FeatureObservation& o : m.observations) uv.push_back(o.uv);
  std::shuffle(uv.begin(), uv.end(), std::mt19937(3));
  for (size_t i = 0; i < uv.size(); ++i) m.observations[i].uv = uv[i];
  return m;
}

MonoInitializerOptions Checked() {
  MonoInitializerOptions o;
  o.next_frame_min_inlier_ratio = 0.5;
  return o;
}

TEST(MonoInitializer, ThePairWaitsForTheNextFrameWhichChecksIt) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), Checked());
  AddTheWeakPair(drive, &init);
  // Frame 2, 1.5 m on, makes a pair with frame 1; it is held until frame 3 sees its points
  // where the pair's motion and depths put them.
  EXPECT_FALSE(init.Add(drive.Frame(2, 1.5, {{50, 80}, {200, 350}, {400, 600}})));
  EXPECT_NE(init.reason().find("checking the pair of frames 1 and 2"), std::string::npos)
      << init.reason();
  const std::optional<MonoInitialization> result =
      init.Add(drive.Frame(3, 1.9, {{200, 350}, {400, 600}}));
  ASSERT_TRUE(result) << init.reason();
  EXPECT_EQ(result->reference.frame, FrameId(1));
  EXPECT_EQ(result->current.frame, FrameId(2));
  ASSERT_TRUE(result->next);
  EXPECT_EQ(result->next->frame, FrameId(3));
  ASSERT_EQ(result->earlier.size(), 1u);
  EXPECT_EQ(result->earlier[0].frame, FrameId(0));
}

// A pair with the reference itself, dropped: the reference stays, the frames after it wait.
TEST(MonoInitializer, ADroppedPairKeepsItsReference) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), Checked());
  EXPECT_FALSE(init.Add(drive.Frame(0, 0.0, {{0, 300}})));
  EXPECT_FALSE(init.Add(drive.Frame(1, 0.05, {{0, 300}})));  // Too little parallax.
  EXPECT_FALSE(init.Add(drive.Frame(2, 1.5, {{0, 300}})));
  EXPECT_NE(init.reason().find("checking the pair of frames 0 and 2"), std::string::npos)
      << init.reason();
  const FrameMeasurement scrambled = Scrambled(drive.Frame(3, 1.9, {{0, 300}}));
  EXPECT_FALSE(init.Add(scrambled));
  EXPECT_NE(init.reason().find("the pair of frames 0 and 2 failed the next frame's check"),
            std::string::npos)
      << init.reason();
  EXPECT_FALSE(init.Add(drive.Frame(4, 2.2, {{0, 300}})));
  const std::optional<MonoInitialization> result = init.Add(drive.Frame(5, 2.5, {{0, 300}}));
  ASSERT_TRUE(result) << init.reason();
  EXPECT_EQ(result->reference.frame, FrameId(0));
  ASSERT_EQ(result->between.size(), 3u);
  EXPECT_EQ(result->between[0].frame, FrameId(1));
  EXPECT_EQ(result->between[2].frame, FrameId(3));
  EXPECT_EQ(result->current.frame, FrameId(4));
  EXPECT_TRUE(result->earlier.empty());
}

// A run that ends while the pair waits: the pair, unchecked.
TEST(MonoInitializer, TheWaitingPairIsHandedOverUncheckedAtTheEnd) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), Checked());
  AddTheWeakPair(drive, &init);
  EXPECT_FALSE(init.TakeWaitingPair());
  EXPECT_FALSE(init.Add(drive.Frame(2, 1.5, {{50, 80}, {200, 350}, {400, 600}})));
  const std::optional<MonoInitialization> pair = init.TakeWaitingPair();
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->reference.frame, FrameId(1));
  EXPECT_EQ(pair->current.frame, FrameId(2));
  EXPECT_FALSE(pair->next);
  EXPECT_FALSE(init.TakeWaitingPair());
}

TEST(MonoInitializer, APairTheNextFrameContradictsIsDropped) {
  const ForwardDrive drive;
  MonoInitializer init(KittiGeometryCamera(), Checked());
  AddTheWeakPair(drive, &init);
  EXPECT_FALSE(init.Add(drive.Frame(2, 1.5, {{50, 80}, {200, 350}, {400, 600}})));
  // Frame 3 sees the pair's points, but each where another one is: no motion explains them.
  const FrameMeasurement scrambled = Scrambled(drive.Frame(3, 1.9, {{200, 350}, {400, 600}}));
  EXPECT_FALSE(init.Add(scrambled));
  EXPECT_NE(init.reason().find("the pair of frames 1 and 2 failed the next frame's check"),
            std::string::npos)
      << init.reason();
  // The initialiser goes on from frame 1: frame 4 makes a pair with it (frames 2 and 3
  // between), which frame 5 keeps.
  EXPECT_FALSE(init.Add(drive.Frame(4, 2.2, {{200, 350}, {400, 600}})));
  const std::optional<MonoInitialization> result =
      init.Add(drive.Frame(5, 2.5, {{200, 350}, {400, 600}}));
  ASSERT_TRUE(result) << init.reason();
  EXPECT_EQ(result->reference.frame, FrameId(1));
  ASSERT_EQ(result->between.size(), 2u);
  EXPECT_EQ(result->between[0].frame, FrameId(2));
  EXPECT_EQ(result->between[1].frame, FrameId(3));
  EXPECT_EQ(result->current.frame, FrameId(4));
  ASSERT_TRUE(result->next);
  EXPECT_EQ(result->next->frame, FrameId(5));
  ASSERT_EQ(result->earlier.size(), 1u);
  EXPECT_EQ(result->earlier[0].frame, FrameId(0));
}

}  // namespace
}  // namespace dala
