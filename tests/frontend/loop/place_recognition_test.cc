// Place recognition (frontend/place_recognition.h) on rendered views with exact poses: the
// revisit of the small loop is found and its PnP pose matches ground truth; a place that looks
// identical but lies 100 m further (false_loop) is verified by appearance and PnP alone, and
// rejected by the spatial gate; a verified pose turned too far from the dead reckoning is too.
#include "frontend/place_recognition.h"

#include <gtest/gtest.h>

#include <unordered_map>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "tests/test_util.h"

namespace dala {
namespace {

struct View {
  FrameId frame;
  Pose T_w_c;
  DetectedImage detection;
  std::vector<std::optional<StereoPoint>> stereo;
  std::vector<LandmarkId> landmark;
  cv::Mat left;
};

View MakeView(const sim::SyntheticSequence& seq, size_t i, int64_t first_landmark) {
  const Frame f = seq.Render(i);
  View v;
  v.frame = f.id;
  v.T_w_c = *f.T_w_c0_gt;
  v.left = f.left;
  const HarrisOptions harris = SequenceHarrisOptions();
  v.detection = DetectHarris(f.left, harris);
  const DetectedImage right = DetectHarris(f.right, harris);
  v.stereo = MatchStereo(seq.rig(), v.detection, right, f.left, f.right, StereoOptions());
  for (size_t k = 0; k < v.detection.points.size(); ++k) {
    v.landmark.push_back(LandmarkId(first_landmark + static_cast<int64_t>(k)));
  }
  return v;
}

KeyframeEntry Entry(const PlaceRecognition& pr, const View& v, const Pose& T_w_c, double path) {
  return pr.MakeEntry(v.frame, 0, T_w_c, path, v.left, v.detection, v.stereo, v.landmark);
}

double RotationDeg(const Pose& T) { return LogSO3(T.linear()).norm() * 180.0 / M_PI; }

TEST(PlaceRecognition, AppearanceScoreRanksTheSamePlaceFirst) {
  sim::SimOptions o;
  o.preset = "small_loop";
  o.stereo = false;
  const sim::SyntheticSequence seq(o);
  const PlaceRecognitionOptions options;
  const cv::Mat a = PlaceRecognition::GlobalDescriptor(seq.Render(0).left, options);
  EXPECT_EQ(a.cols, options.thumbnail_width);
  EXPECT_EQ(a.rows, options.thumbnail_height);
  EXPECT_NEAR(cv::norm(a), 1.0, 1e-5);
  EXPECT_NEAR(PlaceRecognition::AppearanceScore(a, a, options), 1.0, 1e-6);
  // The same place one lap later scores higher than places along the way.
  const double revisit = PlaceRecognition::AppearanceScore(
      a, PlaceRecognition::GlobalDescriptor(seq.Render(seq.size() - 2).left, options), options);
  double best_elsewhere = -1;
  for (size_t i = seq.size() / 8; i < 7 * seq.size() / 8; i += seq.size() / 16) {
    best_elsewhere =
        std::max(best_elsewhere,
                 PlaceRecognition::AppearanceScore(
                     a, PlaceRecognition::GlobalDescriptor(seq.Render(i).left, options), options));
  }
  std::cout << "[ measured ] revisit score " << revisit << ", best elsewhere " << best_elsewhere
            << std::endl;
  // A weak discriminator in the rendered city (8 textures everywhere, near walls and ground
  // change fast): it only ranks the candidates the spatial gate lets through.
  EXPECT_GT(revisit, options.min_appearance_score);
  EXPECT_GT(revisit, best_elsewhere);
}

TEST(PlaceRecognition, FindsTheRevisitAndItsPose) {
  sim::SimOptions o;
  o.preset = "small_loop";
  const sim::SyntheticSequence seq(o);
  PlaceRecognitionOptions options;
  options.min_frame_gap = 50;
  PlaceRecognition pr(seq.rig(), options);
  // Database: keyframes every 40 frames around the loop, at their true poses.
  double path = 0;
  for (size_t i = 0; i + 60 < seq.size(); i += 40) {
    const View v = MakeView(seq, i, 100000 * static_cast<int64_t>(i));
    path = 2.5 * i / o.fps;
    pr.Add(Entry(pr, v, v.T_w_c, path));
  }
  // The revisit, 2 frames before the end (0.5 m before the start), with 2 m of dead-reckoning
  // drift.
  const size_t n = seq.size() - 2;
  const View cur = MakeView(seq, n, 900000000);
  Pose T_w_drifted = cur.T_w_c;
  T_w_drifted.translation() += Eigen::Vector3d(1.5, -1.2, 0.3);
  const KeyframeEntry query = Entry(pr, cur, T_w_drifted, 2.5 * n / o.fps);
  const std::optional<PlaceMatch> match = pr.Detect(query, cur.detection, cur.stereo, cur.landmark);
  const PlaceRecognitionStats& stats = pr.last_stats();
  std::cout << "[ measured ] searched " << stats.searched << ", candidates " << stats.candidates
            << ", best score " << stats.best_score << ", " << stats.ms << " ms" << std::endl;
  ASSERT_TRUE(match.has_value());
  EXPECT_EQ(match->loop.old_frame, FrameId(0));
  const Pose T_old_cur_gt = seq.T_w_c0(0).inverse() * seq.T_w_c0(n);
  const Pose error = T_old_cur_gt.inverse() * match->loop.T_old_cur;
  std::cout << "[ measured ] loop: " << match->loop.inliers << " inliers of "
            << match->loop.correspondences << ", pose error " << error.translation().norm()
            << " m, " << RotationDeg(error) << " deg" << std::endl;
  EXPECT_GE(match->loop.inliers, options.min_inliers);
  EXPECT_LT(error.translation().norm(), 0.02);
  EXPECT_LT(RotationDeg(error), 0.1);
  // Relabelled: each pair maps a current id to an id of the old keyframe, one-to-one.
  ASSERT_EQ(match->loop.relabelled.size(), match->current_point.size());
  EXPECT_GE(static_cast<int>(match->loop.relabelled.size()), options.min_inliers);
  std::set<int64_t> old_ids;
  for (size_t k = 0; k < match->current_point.size(); ++k) {
    EXPECT_EQ(match->loop.relabelled[k].first, cur.landmark[match->current_point[k]]);
    EXPECT_LT(match->loop.relabelled[k].second.value, 100000);  // Keyframe 0's ids.
    EXPECT_TRUE(old_ids.insert(match->loop.relabelled[k].second.value).second);
  }
  // The covariance is a covariance.
  EXPECT_GT(match->loop.cov.ldlt().vectorD().minCoeff(), 0.0);

  // Right after the loop the next keyframes are not searched (keyframes_between_loops).
  EXPECT_FALSE(pr.Detect(query, cur.detection, cur.stereo, cur.landmark).has_value());
  EXPECT_EQ(pr.last_stats().searched, 0);
  // Unless the estimator did not close it: the next keyframe is searched again.
  pr.LoopNotClosed();
  const std::optional<PlaceMatch> again = pr.Detect(query, cur.detection, cur.stereo, cur.landmark);
  EXPECT_GT(pr.last_stats().searched, 0);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->loop.old_frame, FrameId(0));
}

// The gate bounds the orientation too: a verified pose turned from the dead-reckoned one by more
// than gate_rotation_deg + gate_rotation_deg_per_m x path (10.5 deg here) is rejected, as a PnP
// on a repeated facade seen from elsewhere would be; within it, accepted.
TEST(PlaceRecognition, TheGateBoundsTheTurnALoopWouldMake) {
  sim::SimOptions o;
  o.preset = "small_loop";
  const sim::SyntheticSequence seq(o);
  const PlaceRecognitionOptions options;
  const PlaceRecognition pr(seq.rig(), options);
  const View old = MakeView(seq, 0, 0);
  const size_t n = seq.size() - 2;
  const View cur = MakeView(seq, n, 900000000);
  const KeyframeEntry old_entry = Entry(pr, old, old.T_w_c, 0.0);
  const double path = 50.0;
  for (const double yaw_deg : {5.0, 30.0}) {
    // Dead reckoning at the true position, turned about the camera's y axis (down: a yaw).
    Pose T_w_dr = cur.T_w_c;
    T_w_dr.linear() =
        cur.T_w_c.linear() *
        Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
    bool rejected = false;
    const std::optional<PlaceMatch> match =
        pr.Verify(old_entry, Entry(pr, cur, T_w_dr, path), cur.detection, cur.stereo, cur.landmark,
                  &rejected);
    const bool within =
        yaw_deg < options.gate_rotation_deg + options.gate_rotation_deg_per_m * path;
    EXPECT_EQ(match.has_value(), within) << yaw_deg << " deg";
    EXPECT_EQ(rejected, !within) << yaw_deg << " deg";
  }
}

// One entry per place (issue 14): on the second lap of the rover loop, the keyframe that closes
// the loop is held by the old keyframe it matched, and the next ones by the old path's next
// keyframes, so none of them needs an entry of its own; a keyframe where no old one is near is
// not held, nor is any with the option off.
TEST(PlaceRecognition, OneEntryPerPlaceFollowsTheOldPath) {
  sim::SimOptions o;
  o.preset = "rover_loop";
  o.frames = 1060;  // One lap is 1000 frames.
  const sim::SyntheticSequence seq(o);
  PlaceRecognitionOptions options;
  PlaceRecognition pr(seq.rig(), options);
  PlaceRecognitionOptions off = options;
  off.one_entry_per_place = false;
  PlaceRecognition pr_off(seq.rig(), off);
  const double m_per_frame = 1.0 / o.fps;  // Only the spatial gate reads the path: generous.
  for (size_t i = 0; i <= 60; i += 6) {
    const View v = MakeView(seq, i, 100000 * static_cast<int64_t>(i + 1));
    pr.Add(Entry(pr, v, v.T_w_c, m_per_frame * i));
    pr_off.Add(Entry(pr_off, v, v.T_w_c, m_per_frame * i));
  }
  // Far from every entry (frame 500, half-way round): not held.
  const View far = MakeView(seq, 500, 800000000);
  const KeyframeEntry far_query = Entry(pr, far, far.T_w_c, m_per_frame * 500);
  const std::optional<PlaceMatch> no_loop =
      pr.Detect(far_query, far.detection, far.stereo, far.landmark);
  EXPECT_FALSE(no_loop.has_value());
  EXPECT_FALSE(pr.HeldBy(far_query, no_loop, far.detection, far.stereo, far.landmark));

  std::vector<int64_t> holders;
  for (size_t i = 1000; i <= 1030; i += 6) {
    const View cur = MakeView(seq, i, 900000000 + 10000 * static_cast<int64_t>(i));
    const KeyframeEntry query = Entry(pr, cur, cur.T_w_c, m_per_frame * i);
    const std::optional<PlaceMatch> loop =
        pr.Detect(query, cur.detection, cur.stereo, cur.landmark);
    const std::optional<FrameId> held =
        pr.HeldBy(query, loop, cur.detection, cur.stereo, cur.landmark);
    ASSERT_TRUE(held.has_value()) << "frame " << i;
    holders.push_back(held->value);
    // The holder is the old keyframe nearest the current one along the path (within 6 frames).
    EXPECT_LE(std::abs(static_cast<int64_t>(i - 1000) - held->value), 6) << "frame " << i;
    if (i == 1000) {
      ASSERT_TRUE(loop.has_value());
    } else {
      EXPECT_FALSE(loop.has_value());  // keyframes_between_loops: no loop search, yet held.
    }
    const KeyframeEntry query_off = Entry(pr_off, cur, cur.T_w_c, m_per_frame * i);
    const std::optional<PlaceMatch> loop_off =
        pr_off.Detect(query_off, cur.detection, cur.stereo, cur.landmark);
    EXPECT_FALSE(pr_off.HeldBy(query_off, loop_off, cur.detection, cur.stereo, cur.landmark));
  }
  std::cout << "[ measured ] holders:";
  for (int64_t h : holders) std::cout << " " << h;
  std::cout << std::endl;
}

// One camera: the keyframes keep their points without depth, and the revisit is verified by
// the epipolar geometry (or a rotation's homography); the gate is a fraction of the path in map
// units. The relabelled points must be keyframe 0's, and the model's rotation the true one.
TEST(PlaceRecognition, OneCameraFindsTheRevisitByItsEpipolarGeometry) {
  sim::SimOptions o;
  o.preset = "small_loop";
  const sim::SyntheticSequence seq(o);
  StereoRig mono = seq.rig();
  mono.baseline = 0;
  PlaceRecognitionOptions options;
  options.min_frame_gap = 50;
  PlaceRecognition pr(mono, options);
  const auto mono_view = [&](size_t i, int64_t first_landmark) {
    View v = MakeView(seq, i, first_landmark);
    v.stereo.assign(v.stereo.size(), std::nullopt);
    return v;
  };
  for (size_t i = 0; i + 60 < seq.size(); i += 40) {
    const View v = mono_view(i, 100000 * static_cast<int64_t>(i));
    const KeyframeEntry e = Entry(pr, v, v.T_w_c, 2.5 * i / o.fps);
    EXPECT_EQ(static_cast<int>(e.size()),
              std::min<int>(options.mono_max_entry_points, v.detection.points.size()));
    pr.Add(e);
  }
  const size_t n = seq.size() - 2;
  const View cur = mono_view(n, 900000000);
  Pose T_w_drifted = cur.T_w_c;
  T_w_drifted.translation() += Eigen::Vector3d(1.5, -1.2, 0.3);
  const KeyframeEntry query = Entry(pr, cur, T_w_drifted, 2.5 * n / o.fps);
  const std::optional<PlaceMatch> match = pr.Detect(query, cur.detection, cur.stereo, cur.landmark);
  ASSERT_TRUE(match.has_value());
  EXPECT_EQ(match->loop.old_frame, FrameId(0));
  const Pose T_old_cur_gt = seq.T_w_c0(0).inverse() * seq.T_w_c0(n);
  const double rotation_error_deg = RotationDeg(
      MakePose(T_old_cur_gt.linear().transpose() * match->loop.T_old_cur.linear(),
               Eigen::Vector3d::Zero()));
  std::cout << "[ measured ] mono loop: " << match->loop.inliers << " inliers of "
            << match->loop.correspondences << ", rotation error " << rotation_error_deg << " deg"
            << std::endl;
  EXPECT_LT(rotation_error_deg, 0.5);
  EXPECT_GE(static_cast<int>(match->loop.relabelled.size()), options.min_inliers);
  for (const auto& [cur_id, old_id] : match->loop.relabelled) EXPECT_LT(old_id.value, 100000);
}

TEST(PlaceRecognition, NoLoopHalfWayRound) {
  sim::SimOptions o;
  o.preset = "small_loop";
  const sim::SyntheticSequence seq(o);
  PlaceRecognitionOptions options;
  options.min_frame_gap = 50;
  options.spatial_gate = false;  // Appearance and verification alone.
  PlaceRecognition pr(seq.rig(), options);
  for (size_t i : {size_t{0}, size_t{40}, size_t{80}}) {
    const View v = MakeView(seq, i, 100000 * static_cast<int64_t>(i));
    pr.Add(Entry(pr, v, v.T_w_c, 0));
  }
  const size_t n = seq.size() / 2;
  const View cur = MakeView(seq, n, 900000000);
  EXPECT_FALSE(pr.Detect(Entry(pr, cur, cur.T_w_c, 60), cur.detection, cur.stereo, cur.landmark));
}

// false_loop: x = 50 m and x = 150 m are the same buildings. Matcher and PnP verify the
// look-alike (so the preset does what it says), the spatial gate rejects it.
TEST(PlaceRecognition, LookAlikePlaceIsRejectedByTheSpatialGate) {
  sim::SimOptions o;
  o.preset = "false_loop";
  const sim::SyntheticSequence seq(o);
  const size_t a = 250, b = 750;  // x = 50 m, 150 m (2 m/s, 10 Hz).
  ASSERT_NEAR(seq.T_w_c0(b).translation().x() - seq.T_w_c0(a).translation().x(), 100.0, 1e-6);
  PlaceRecognitionOptions options;
  PlaceRecognition pr(seq.rig(), options);
  const View old = MakeView(seq, a, 0);
  const View cur = MakeView(seq, b, 900000000);
  // Dead reckoning with a 2 % drift: 2 m off after 100 m.
  Pose T_w_cur_dr = cur.T_w_c;
  T_w_cur_dr.translation().x() -= 2.0;
  pr.Add(Entry(pr, old, old.T_w_c, 50.0));
  const KeyframeEntry query = Entry(pr, cur, T_w_cur_dr, 150.0);

  const double score = PlaceRecognition::AppearanceScore(
      pr.database().entries()[0].global_descriptor, query.global_descriptor, options);
  std::cout << "[ measured ] look-alike appearance score " << score << std::endl;
  EXPECT_GT(score, options.min_appearance_score);

  // Without the gate: verified (the places really look the same, geometry included).
  PlaceRecognitionOptions no_gate = options;
  no_gate.spatial_gate = false;
  const PlaceRecognition pr_no_gate(seq.rig(), no_gate);
  const std::optional<PlaceMatch> fooled =
      pr_no_gate.Verify(pr.database().entries()[0], query, cur.detection, cur.stereo, cur.landmark);
  ASSERT_TRUE(fooled.has_value());
  EXPECT_LT(fooled->loop.T_old_cur.translation().norm(), 1.0);  // "Same place".

  // With the gate: the entry is 98 m from the dead-reckoned position, 100 m of path apart.
  EXPECT_FALSE(pr.Detect(query, cur.detection, cur.stereo, cur.landmark).has_value());
  EXPECT_EQ(pr.last_stats().searched, 1);
  EXPECT_EQ(pr.last_stats().gated_out, 1);
  bool rejected = false;
  EXPECT_FALSE(pr.Verify(pr.database().entries()[0], query, cur.detection, cur.stereo, cur.landmark,
                         &rejected));
  EXPECT_TRUE(rejected);
}

TEST(PlaceRecognition, InvalidOptionsAreRejected) {
  std::string why;
  PlaceRecognitionOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.max_shift_x = o.thumbnail_width;
  EXPECT_FALSE(o.IsValid(&why));
  o = PlaceRecognitionOptions();
  o.min_inliers = 5;  // Below the PnP's own minimum.
  EXPECT_FALSE(o.IsValid(&why));
  o = PlaceRecognitionOptions();
  o.top_k = 0;
  EXPECT_FALSE(o.IsValid(&why));
  o = PlaceRecognitionOptions();
  o.gate_radius_m = 0;
  EXPECT_FALSE(o.IsValid(&why));
  o = PlaceRecognitionOptions();
  o.gate_rotation_deg = 0;
  EXPECT_FALSE(o.IsValid(&why));
  o = PlaceRecognitionOptions();
  o.gate_rotation_deg_per_m = -0.01;
  EXPECT_FALSE(o.IsValid(&why));
}

TEST(KeyframeDatabase, AddFindAndOrder) {
  KeyframeDatabase db;
  KeyframeEntry e;
  e.frame = FrameId(3);
  e.descriptors = QuantizedDescriptors(121);
  db.Add(e);
  e.frame = FrameId(7);
  db.Add(e);
  ASSERT_NE(db.Find(FrameId(7)), nullptr);
  EXPECT_EQ(db.Find(FrameId(7))->frame, FrameId(7));
  EXPECT_EQ(db.Find(FrameId(5)), nullptr);
  EXPECT_EQ(db.size(), 2u);
  e.frame = FrameId(6);
  EXPECT_DEATH(db.Add(e), "increase");
  e.frame = FrameId(9);
  e.landmark.push_back(LandmarkId(1));  // One id, no point.
  EXPECT_DEATH(db.Add(e), "one point per landmark");
}

// A refused loop's points take back their ids (Frontend::ReturnLoopIds) in the keyframe's entry.
TEST(KeyframeDatabase, RenameLandmarksRenamesOneEntry) {
  KeyframeDatabase db;
  KeyframeEntry e;
  e.descriptors = QuantizedDescriptors(2);
  const std::vector<float> row = {0.5f, -0.5f};
  for (const int id : {10, 11, 12}) {
    e.points.emplace_back();
    e.descriptors.Append(row.data());
    e.landmark.push_back(LandmarkId(id));
    e.stereo.emplace_back();
  }
  e.frame = FrameId(3);
  db.Add(e);
  e.frame = FrameId(7);
  db.Add(e);
  const std::unordered_map<LandmarkId, LandmarkId> before = {{LandmarkId(11), LandmarkId(40)},
                                                              {LandmarkId(12), LandmarkId()}};
  EXPECT_TRUE(db.RenameLandmarks(FrameId(7), before));
  EXPECT_FALSE(db.RenameLandmarks(FrameId(5), before));
  EXPECT_EQ(db.Find(FrameId(7))->landmark,
            (std::vector<LandmarkId>{LandmarkId(10), LandmarkId(40), LandmarkId()}));
  EXPECT_EQ(db.Find(FrameId(3))->landmark,
            (std::vector<LandmarkId>{LandmarkId(10), LandmarkId(11), LandmarkId(12)}));
}

}  // namespace
}  // namespace dala
