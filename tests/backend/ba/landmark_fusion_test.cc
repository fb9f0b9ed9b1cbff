// SlidingWindowBa::FuseLandmarks: a point whose track broke and restarted under a new id is
// merged back; a different point that only projects to the same pixel is not.

#include <gtest/gtest.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "backend/ba/sliding_window_ba.h"
#include "tests/backend/ba/ba_synthetic_scene.h"

namespace dala {
namespace {

using testing::BaScene;
using testing::BaSceneOptions;
using testing::MakeBaScene;

constexpr int kNumKeyframes = 6;
constexpr int kBreak = 3;  // The broken tracks change id from this keyframe on.

Eigen::Vector2d Project(const BaScene& scene, int keyframe, const Eigen::Vector3d& p_w) {
  const Eigen::Vector3d q = scene.T_w_c_gt[keyframe].inverse() * p_w;
  return {scene.K.fx * q.x() / q.z() + scene.K.cx, scene.K.fy * q.y() / q.z() + scene.K.cy};
}

// The landmark seen by every keyframe that is nearest to the last one (the most parallax).
LandmarkId NearestLandmarkSeenByAll(const BaScene& scene, const std::vector<LandmarkId>& avoid) {
  LandmarkId best;
  double best_distance = 1e9;
  for (size_t j = 0; j < scene.p_w_gt.size(); ++j) {
    const LandmarkId id(static_cast<int64_t>(j));
    if (std::find(avoid.begin(), avoid.end(), id) != avoid.end()) continue;
    bool seen_by_all = true;
    for (const BaKeyframe& kf : scene.keyframes) {
      seen_by_all =
          seen_by_all && std::any_of(kf.observations.begin(), kf.observations.end(),
                                     [&](const BaObservation& o) { return o.landmark == id; });
    }
    const double d = (scene.T_w_c_gt[kNumKeyframes - 1].inverse() * scene.p_w_gt[j]).z();
    if (seen_by_all && d < best_distance) {
      best_distance = d;
      best = id;
    }
  }
  return best;
}

class LandmarkFusionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    BaSceneOptions o;
    o.num_keyframes = kNumKeyframes;
    o.num_points = 200;
    o.stereo = false;
    o.pixel_noise = 0.3;
    scene_ = MakeBaScene(o);
    broken_ = NearestLandmarkSeenByAll(scene_, {});
    occluded_ = NearestLandmarkSeenByAll(scene_, {broken_});
    ASSERT_TRUE(broken_.valid() && occluded_.valid());
    for (int k = kBreak; k < kNumKeyframes; ++k) {
      auto& obs = scene_.keyframes[k].observations;
      for (BaObservation& b : obs) {
        if (b.landmark == broken_) b.landmark = restarted_;
      }
      // `occluded_` is not seen from kBreak on; `impostor_` is a different point on the last
      // keyframe's ray through it, at 0.6 of its depth, seen from kBreak on.
      obs.erase(std::remove_if(obs.begin(), obs.end(),
                               [&](const BaObservation& b) { return b.landmark == occluded_; }),
                obs.end());
    }
    const Pose& T_w_last = scene_.T_w_c_gt[kNumKeyframes - 1];
    const Eigen::Vector3d p_occluded = scene_.p_w_gt[static_cast<size_t>(occluded_.value)];
    const Eigen::Vector3d p_impostor = T_w_last * (0.6 * (T_w_last.inverse() * p_occluded));
    for (int k = kBreak; k < kNumKeyframes; ++k) {
      BaObservation b;
      b.landmark = impostor_;
      b.uv = Project(scene_, k, p_impostor);
      b.sigma_px = 0.3;
      scene_.keyframes[k].observations.push_back(b);
    }
  }

  // Every keyframe added at its true pose and the window solved after each one.
  void Run(SlidingWindowBa* ba) {
    for (const BaKeyframe& kf : scene_.keyframes) {
      ba->AddKeyframe(kf);
      ASSERT_TRUE(ba->Optimize().usable);
    }
  }

  BaScene scene_;
  LandmarkId broken_, occluded_;
  const LandmarkId restarted_ = LandmarkId(100000);
  const LandmarkId impostor_ = LandmarkId(100001);
};

TEST_F(LandmarkFusionTest, ARestartedTrackIsMergedIntoItsOlderIdAndAnImpostorIsNot) {
  SlidingWindowBa::Options options;
  options.fuse_radius_px = 4.0;
  SlidingWindowBa ba(scene_.K, options);
  Run(&ba);
  ASSERT_TRUE(ba.LandmarkPosition(broken_) && ba.LandmarkPosition(restarted_));
  ASSERT_TRUE(ba.LandmarkPosition(occluded_) && ba.LandmarkPosition(impostor_));
  // At the estimates, the occluded point projects within the radius of the impostor's view in
  // the last keyframe: the impostor is a candidate twin that only the other views can refuse.
  const Pose T_last_w = ba.KeyframePose(KeyframeId(kNumKeyframes - 1))->inverse();
  const Eigen::Vector3d q = T_last_w * *ba.LandmarkPosition(occluded_);
  const Eigen::Vector2d uv_occluded(scene_.K.fx * q.x() / q.z() + scene_.K.cx,
                                    scene_.K.fy * q.y() / q.z() + scene_.K.cy);
  EXPECT_LT((uv_occluded - scene_.keyframes.back().observations.back().uv).norm(),
            options.fuse_radius_px);

  const std::vector<std::pair<LandmarkId, LandmarkId>> fused = ba.FuseLandmarks();
  ASSERT_EQ(fused.size(), 1u);
  EXPECT_EQ(fused[0].first, restarted_);
  EXPECT_EQ(fused[0].second, broken_);
  EXPECT_FALSE(ba.LandmarkPosition(restarted_));
  EXPECT_EQ(ba.ObservingKeyframes(broken_).size(), static_cast<size_t>(kNumKeyframes));
  EXPECT_LT(
      (*ba.LandmarkPosition(broken_) - scene_.p_w_gt[static_cast<size_t>(broken_.value)]).norm(),
      0.05);
  EXPECT_EQ(ba.ObservingKeyframes(impostor_).size(), static_cast<size_t>(kNumKeyframes - kBreak));
  // The merged landmark is solved with all its views.
  EXPECT_TRUE(ba.Optimize().usable);
  EXPECT_EQ(ba.ObservingKeyframes(broken_).size(), static_cast<size_t>(kNumKeyframes));
}

TEST_F(LandmarkFusionTest, OffByDefault) {
  SlidingWindowBa ba(scene_.K, SlidingWindowBa::Options());
  Run(&ba);
  EXPECT_TRUE(ba.FuseLandmarks().empty());
  EXPECT_TRUE(ba.LandmarkPosition(restarted_));
}

}  // namespace
}  // namespace dala
