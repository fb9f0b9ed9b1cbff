#include "frontend/frontend.h"

#include <glog/logging.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "core/error.h"

namespace dala {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Distance in pixels of the current point from the epipolar line of the previous one, for the
// motion T_cur_prev = (R, t): E = [t]x R, line l = E x_prev in normalised coordinates.
double EpipolarDistancePx(const PinholeCamera& cam, const Pose& T_cur_prev,
                          const Eigen::Vector2d& uv_prev, const Eigen::Vector2d& uv_cur) {
  const Eigen::Vector3d t = T_cur_prev.translation();
  if (t.norm() < 1e-9) {
    // Pure rotation: the point must land where the rotation sends it.
    Eigen::Vector2d uv;
    if (!cam.Project(T_cur_prev.linear() * cam.Unproject(uv_prev), &uv)) {
      return std::numeric_limits<double>::infinity();
    }
    return (uv - uv_cur).norm();
  }
  const Eigen::Matrix3d E = Skew(t.normalized()) * T_cur_prev.linear();
  const Eigen::Vector3d l = E * cam.Unproject(uv_prev);
  const double n = l.head<2>().norm();
  if (n < 1e-12) return std::numeric_limits<double>::infinity();
  return std::abs(cam.Unproject(uv_cur).dot(l)) / n * cam.fx;
}

}  // namespace

HarrisOptions SequenceHarrisOptions() {
  HarrisOptions options;
  options.num_levels = 2;
  options.max_points = 1000;
  options.max_per_cell = 2;
  return options;
}

bool FrontendOptions::IsValid(std::string* why) const {
  if (!harris.IsValid(why) || !stereo.IsValid(why) || !tracking_matcher.IsValid(why) ||
      !motion.IsValid(why) || !keyframe.IsValid(why) || !loop.IsValid(why) ||
      !local_map.IsValid(why)) {
    return false;
  }
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (tracking_radius_px <= 0) return fail("frontend.tracking_radius_px must be > 0");
  if (epipolar_gate_px <= 0) return fail("frontend.epipolar_gate_px must be > 0");
  if (keyframe_gate_px <= 0) return fail("frontend.keyframe_gate_px must be > 0");
  if (!(mono_free_matching_below >= 0 && mono_free_matching_below <= 1))
    return fail("frontend.mono_free_matching_below must be in [0, 1]");
  return true;
}

Frontend::Frontend(const StereoRig& rig, const FrontendOptions& options)
    : rig_(rig),
      options_(options),
      motion_estimator_(rig, options.motion),
      keyframe_policy_(options.keyframe),
      place_recognition_(rig, options.loop),
      local_map_search_(rig.left, options.local_map, options.tracking_matcher, rig.is_stereo()) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
  CHECK(rig_.left.IsValid(&why)) << why;
}

std::vector<Match> Frontend::MatchTemporal(
    const TrackedFrame& from, const DetectedImage& cur, const Pose* T_from_cur,
    const std::vector<std::optional<Eigen::Vector3d>>* p_from) const {
  if (T_from_cur == nullptr) {
    MatcherOptions unconstrained = options_.tracking_matcher;
    unconstrained.max_rotation = 3.2;
    return MatchPoints(from.detection, cur, unconstrained);
  }
  const Pose T_cur_from = T_from_cur->inverse();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Eigen::Vector2d> predicted(from.detection.points.size(), Eigen::Vector2d(nan, nan));
  for (size_t i = 0; i < predicted.size(); ++i) {
    Eigen::Vector3d p_cur;
    if (p_from != nullptr && (*p_from)[i]) {
      p_cur = T_cur_from * *(*p_from)[i];
    } else if (from.stereo[i]) {
      p_cur = T_cur_from * from.stereo[i]->p_c0;
    } else {
      // No depth: a point at infinity moves with the rotation only.
      p_cur = T_cur_from.linear() * rig_.left.Unproject(from.detection.points[i].uv);
    }
    Eigen::Vector2d uv;
    if (rig_.left.Project(p_cur, &uv)) predicted[i] = uv;
  }
  const MatchPrior prior = MatchPrior::Predicted(std::move(predicted), options_.tracking_radius_px);
  return MatchPoints(from.detection, cur, options_.tracking_matcher, &prior);
}

std::optional<MotionEstimate> Frontend::TrackFromPrevious(
    TrackedFrame* cur, std::optional<std::vector<Match>> predicted_matches) {
  const TrackedFrame& prev = *prev_;
  Pose prediction = velocity_T_prev_cur_;
  // One camera: the estimator's map gives the previous points their depth (and the velocity its
  // unit), as the stereo points do in stereo (frontend/local_map_search.h).
  std::optional<LocalMapSearch::Prediction> from_map;
  if (!rig_.is_stereo()) {
    from_map = local_map_search_.PredictFromMap(prev.id, prev.landmark, prev.detection);
    if (from_map) prediction = from_map->T_prev_cur;
  }
  // One attempt: matches (around the prediction, or without a prior) and the motion.
  struct Attempt {
    std::vector<Match> matches;
    std::vector<int> corr_match;  // Correspondence -> index in matches.
    std::optional<MotionResult> motion;
  };
  const auto attempt_with = [&](const Pose* prior, std::optional<std::vector<Match>> given) {
    Attempt a;
    a.matches = given ? std::move(*given)
                      : MatchTemporal(prev, cur->detection, prior,
                                      from_map ? &from_map->p_prev : nullptr);
    if (rig_.is_stereo()) {
      std::vector<MotionCorrespondence> corrs;
      for (size_t k = 0; k < a.matches.size(); ++k) {
        const Match& m = a.matches[k];
        if (!prev.stereo[m.i]) continue;
        MotionCorrespondence c;
        c.p_prev = prev.stereo[m.i]->p_c0;
        c.cov_p_prev = prev.stereo[m.i]->cov_p_c0;
        c.uv_cur = cur->detection.points[m.j].uv;
        if (cur->stereo[m.j]) c.u_right_cur = cur->stereo[m.j]->u_right;
        corrs.push_back(c);
        a.corr_match.push_back(static_cast<int>(k));
      }
      a.motion = motion_estimator_.Estimate3D2D(corrs, &prediction);
    } else {
      std::vector<Eigen::Vector2d> uv_prev, uv_cur;
      for (size_t k = 0; k < a.matches.size(); ++k) {
        uv_prev.push_back(prev.detection.points[a.matches[k].i].uv);
        uv_cur.push_back(cur->detection.points[a.matches[k].j].uv);
        a.corr_match.push_back(static_cast<int>(k));
      }
      a.motion = motion_estimator_.EstimateEssential(uv_prev, uv_cur);
      // No epipolar geometry (pure rotation), or a degenerate one that keeps few of the matches
      // (a plane: flying over flat ground): the homography verifies the tracks instead, so the
      // landmark ids live on (and the estimator can say why it does not start).
      // A track is kept when either model verifies it (the union of the inliers), the motion
      // is the model with more inliers.
      if (!a.motion || 2 * a.motion->estimate.inliers < static_cast<int>(a.matches.size())) {
        std::optional<MotionResult> h = motion_estimator_.EstimateRotation(uv_prev, uv_cur);
        if (h && a.motion) {
          MotionResult& best = h->estimate.inliers > a.motion->estimate.inliers ? *h : *a.motion;
          const MotionResult& other = &best == &*h ? *a.motion : *h;
          for (size_t k = 0; k < best.inlier.size(); ++k) {
            best.inlier[k] = best.inlier[k] || other.inlier[k];
          }
          best.estimate.inliers =
              static_cast<int>(std::count(best.inlier.begin(), best.inlier.end(), true));
          if (&best == &*h) a.motion = std::move(h);
        } else if (h) {
          a.motion = std::move(h);
        }
      }
    }
    return a;
  };
  // The motion's inliers whose previous point is one of the map's (from_map->mapped).
  const auto mapped_inliers = [&](const Attempt& a) {
    int n = 0;
    if (!a.motion || !from_map) return n;
    for (size_t c = 0; c < a.corr_match.size(); ++c) {
      n += a.motion->inlier[c] && from_map->mapped[a.matches[a.corr_match[c]].i];
    }
    return n;
  };
  Attempt best = attempt_with(&prediction, std::move(predicted_matches));
  if (!best.motion) {
    // A jerk: matching without a prior, as for a loop closure.
    best = attempt_with(nullptr, std::nullopt);
  } else if (!rig_.is_stereo() && !from_map &&
             best.motion->estimate.inliers <
                 options_.mono_free_matching_below *
                     static_cast<double>(prev.detection.points.size())) {
    // One camera before its map exists: no point has a depth, so each is predicted where a
    // point at infinity would go (the rotation only) and searched within tracking_radius_px.
    // Moving fast forward, the near points (the parallax the two-view initialisation needs)
    // land beyond that radius and only the far ones are kept: match without a prior as well,
    // keep the attempt with more inliers.
    Attempt unconstrained = attempt_with(nullptr, std::nullopt);
    if (unconstrained.motion &&
        unconstrained.motion->estimate.inliers > best.motion->estimate.inliers) {
      best = std::move(unconstrained);
    }
  } else if (from_map && (best.motion->estimate.inliers < from_map->num_mapped / 2 ||
                          mapped_inliers(best) < from_map->num_mapped / 2)) {
    // One camera: the map-predicted matches keep less than half of the mapped points (a turn
    // the constant velocity did not foresee): match without a prior as well. The free matching
    // is kept when it keeps more inliers where the prediction kept few, or when it keeps
    // kFreeMatchingMinGain times the prediction's mapped points: those are what the estimator
    // places the frame by, and a jerk can keep far unmapped points and lose the map (rendered
    // fast seed 7, frame 90: 86 inliers, 2 of them mapped out of 53; the map was lost for ten
    // frames). On a smooth path both keep about as many mapped points (rover loop seed 2: the
    // free one 0.8-1.33x in 56 of 58 such frames, median 1.0x, 2x once); after a jerk the free
    // one keeps many more (fast seeds 1, 7, 8: 2x or more in 190 of 211, median 6-8x).
    constexpr double kFreeMatchingMinGain = 2.0;
    Attempt unconstrained = attempt_with(nullptr, std::nullopt);
    if (unconstrained.motion) {
      const int kept_predicted = mapped_inliers(best);
      const int kept_free = mapped_inliers(unconstrained);
      VLOG(2) << "frame " << cur->id << ": map-predicted matching keeps " << kept_predicted
              << " of " << from_map->num_mapped << " mapped points, free matching " << kept_free;
      const bool more_inliers = best.motion->estimate.inliers < from_map->num_mapped / 2 &&
                                unconstrained.motion->estimate.inliers >
                                    best.motion->estimate.inliers;
      if (more_inliers || kept_free >= kFreeMatchingMinGain * std::max(kept_predicted, 1)) {
        best = std::move(unconstrained);
      }
    }
  }
  if (!rig_.is_stereo() && !from_map && estimator_initializing_ && best.motion &&
      options_.mono_init_rematch) {
    // One camera while the two-view initialisation waits: no point has a depth, so each was
    // searched around where the constant rotation rate alone sends it. When the frame's own
    // rotation differs from that prediction by more than half the search radius (the yaw rate
    // changed: a turn's start or end), the points it sent farthest are not in the tracks and
    // the reference frame's tracks thin out before the parallax is reached; matching again
    // around the estimated rotation finds them (a point without depth moves with the rotation).
    const Eigen::Matrix3d& R_est = best.motion->estimate.T_prev_cur.linear();
    const double turned = LogSO3(prediction.linear().transpose() * R_est).norm();
    if (turned > 0.5 * options_.tracking_radius_px / rig_.left.fx) {
      Pose rotation = Pose::Identity();
      rotation.linear() = R_est;
      Attempt again = attempt_with(&rotation, std::nullopt);
      if (again.motion && again.motion->estimate.inliers > best.motion->estimate.inliers) {
        best = std::move(again);
      }
    }
  }
  const std::vector<Match>& matches = best.matches;
  const std::vector<int>& corr_match = best.corr_match;
  std::optional<MotionResult>& motion = best.motion;
  VLOG(2) << "frame " << cur->id << ": " << matches.size() << " temporal matches, "
          << (motion ? std::to_string(motion->estimate.inliers) + " motion inliers"
                     : std::string("no motion"))
          << (from_map ? " (map-predicted)" : "");
  if (!motion) return std::nullopt;

  // Ids through the motion's inliers, then the depth-less matches through the epipolar gate.
  std::vector<bool> decided(matches.size(), false);
  for (size_t c = 0; c < corr_match.size(); ++c) {
    const Match& m = matches[corr_match[c]];
    decided[corr_match[c]] = true;
    if (!motion->inlier[c]) continue;
    cur->landmark[m.j] = prev.landmark[m.i];
    cur->track_length[m.j] = prev.track_length[m.i] + 1;
  }
  const Pose T_cur_prev = motion->estimate.T_prev_cur.inverse();
  for (size_t k = 0; k < matches.size(); ++k) {
    if (decided[k]) continue;
    const Match& m = matches[k];
    if (EpipolarDistancePx(rig_.left, T_cur_prev, prev.detection.points[m.i].uv,
                           cur->detection.points[m.j].uv) < options_.epipolar_gate_px) {
      cur->landmark[m.j] = prev.landmark[m.i];
      cur->track_length[m.j] = prev.track_length[m.i] + 1;
    }
  }
  return motion->estimate;
}

void Frontend::ReacquireFromKeyframe(TrackedFrame* cur) const {
  const TrackedFrame& kf = *keyframe_;
  std::unordered_set<LandmarkId> present;
  for (const LandmarkId& id : cur->landmark) {
    if (id.valid()) present.insert(id);
  }
  const Pose T_kf_cur = kf.T_w_c.inverse() * cur->T_w_c;
  const Pose T_cur_kf = T_kf_cur.inverse();
  const std::vector<Match> matches = MatchTemporal(kf, cur->detection, &T_kf_cur);
  for (const Match& m : matches) {
    if (cur->landmark[m.j].valid() || !kf.landmark[m.i].valid() ||
        present.count(kf.landmark[m.i])) {
      continue;
    }
    const Eigen::Vector2d& uv_cur = cur->detection.points[m.j].uv;
    double error = std::numeric_limits<double>::infinity();
    if (kf.stereo[m.i]) {
      Eigen::Vector2d uv;
      if (rig_.left.Project(T_cur_kf * kf.stereo[m.i]->p_c0, &uv)) error = (uv - uv_cur).norm();
    } else {
      error = EpipolarDistancePx(rig_.left, T_cur_kf, kf.detection.points[m.i].uv, uv_cur);
    }
    if (error > options_.keyframe_gate_px) continue;
    cur->landmark[m.j] = kf.landmark[m.i];
    cur->track_length[m.j] = kf.track_length[m.i] + 1;
    present.insert(kf.landmark[m.i]);
  }
}

void Frontend::UseMap(const SavedMap& map) {
  CHECK(!prev_) << "Frontend::UseMap before the first frame";
  std::unordered_map<LandmarkId, Eigen::Vector3d> p_w;
  for (const SavedLandmark& l : map.landmarks) {
    p_w[l.id] = l.p_w;
    next_landmark_ = std::max(next_landmark_, l.id.value + 1);
  }
  for (const SavedKeyframe& kf : map.keyframes) {
    for (const SavedKeyframePoint& p : kf.points) {
      next_landmark_ = std::max(next_landmark_, p.landmark.value + 1);
    }
    place_recognition_.AddSavedKeyframe(kf, options_.harris.patch_size,
                                        options_.harris.patch_spacing, p_w);
  }
  awaiting_map_ = true;
}

bool Frontend::RelocalizeFromDatabase(const Frame& frame, TrackedFrame* cur) {
  if (!options_.loop.enable || !options_.loop.relocalise ||
      place_recognition_.database().size() + place_recognition_.saved_map_database().size() == 0 ||
      static_cast<int>(cur->detection.points.size()) < options_.loop.min_inliers) {
    return false;
  }
  // One camera: no point has a depth here; the entry keeps the strongest corners with an id.
  const std::vector<std::optional<StereoPoint>> no_depth(cur->detection.points.size());
  const std::vector<std::optional<StereoPoint>>& points = rig_.is_stereo() ? cur->stereo : no_depth;
  const KeyframeEntry query =
      place_recognition_.MakeEntry(frame.id, frame.t_ns, cur->T_w_c, path_length_m_, frame.left,
                                   cur->detection, points, cur->landmark);
  const std::optional<PlaceMatch> match =
      place_recognition_.Relocalize(query, cur->detection, cur->stereo, cur->landmark);
  const PlaceRecognitionStats& stats = place_recognition_.last_stats();
  if (!match) {
    VLOG(1) << "frame " << frame.id << ": lost; no place recognised among " << stats.searched
            << " keyframes (best appearance " << stats.best_score << ", " << stats.candidates
            << " verified)";
    return false;
  }
  int relabelled = 0;
  for (size_t k = 0; k < match->current_point.size(); ++k) {
    LandmarkId& id = cur->landmark[match->current_point[k]];
    if (local_map_search_.IsMapped(id)) continue;  // Found again by RelocalizeFromKeyframe.
    id = match->loop.relabelled[k].second;
    ++relabelled;
  }
  VLOG(1) << "frame " << frame.id << ": lost; relocalised at the place of keyframe "
          << match->loop.old_frame << " (" << match->loop.inliers << " inliers, " << relabelled
          << " points take its landmark ids)";
  return relabelled > 0;
}

void Frontend::RelocalizeFromKeyframe(TrackedFrame* cur) const {
  // No pose to predict with: the matcher's group constraints alone (any rotation), and only
  // the landmarks the estimator maps, which it verifies (RANSAC PnP) before using them.
  std::unordered_set<LandmarkId> present;
  for (const LandmarkId& id : cur->landmark) {
    if (id.valid()) present.insert(id);
  }
  int assigned = 0;
  const TrackedFrame& kf = *tracked_keyframe_;
  for (const Match& m : MatchTemporal(kf, cur->detection, nullptr)) {
    const LandmarkId id = kf.landmark[m.i];
    if (cur->landmark[m.j].valid() || !local_map_search_.IsMapped(id) || present.count(id)) {
      continue;
    }
    cur->landmark[m.j] = id;
    cur->track_length[m.j] = kf.track_length[m.i] + 1;
    present.insert(id);
    ++assigned;
  }
  VLOG(1) << "frame " << cur->id << ": lost before; " << assigned
          << " mapped landmarks of keyframe " << kf.id << " found again";
}

std::optional<LoopDetection> Frontend::DetectLoop(const Frame& frame,
                                                  const std::optional<MotionEstimate>& motion,
                                                  TrackedFrame* cur,
                                                  std::optional<FrameId>* held_by) {
  // Stereo: the keyframe's stereo points and the dead-reckoned pose (metres). One camera: its
  // mapped landmarks, at the estimator's predicted pose (map units).
  Pose T_w_c = cur->T_w_c;
  double path_length = path_length_m_;
  const std::vector<std::optional<StereoPoint>>* points = &cur->stereo;
  std::optional<LocalMapSearch::MappedPoints> mapped;
  if (!rig_.is_stereo()) {
    std::optional<Pose> T_prev_cur;
    if (motion) T_prev_cur = motion->T_prev_cur;
    mapped = local_map_search_.MappedPointsInCamera(prev_->id, T_prev_cur, cur->landmark);
    if (!mapped) return std::nullopt;
    T_w_c = mapped->T_w_c;
    path_length = mapped->path_length;
    points = &mapped->points;
  }
  KeyframeEntry entry = place_recognition_.MakeEntry(frame.id, frame.t_ns, T_w_c, path_length,
                                                     frame.left, cur->detection, *points,
                                                     cur->landmark);
  std::optional<PlaceMatch> match =
      place_recognition_.Detect(entry, cur->detection, cur->stereo, cur->landmark);
  if (match) {
    std::unordered_map<LandmarkId, LandmarkId> old_of;
    for (size_t k = 0; k < match->current_point.size(); ++k) {
      cur->landmark[match->current_point[k]] = match->loop.relabelled[k].second;
      old_of[match->loop.relabelled[k].first] = match->loop.relabelled[k].second;
    }
    RenameLandmarkIds(old_of, &entry.landmark);
  }
  const PlaceRecognitionStats& stats = place_recognition_.last_stats();
  VLOG(stats.candidates > 0 ? 1 : 2)
      << "frame " << frame.id << ": place recognition over " << stats.searched << " keyframes ("
      << stats.gated_out << " out of the gate), " << stats.candidates << " verified, best "
      << stats.best_score << " (frame " << stats.best_frame << ")"
      << (stats.rejected_by_gate ? ", a PnP pose outside the gate" : "")
      << (match ? ", loop to frame " + std::to_string(match->loop.old_frame.value) : "");
  // One entry per place: a keyframe whose place an older entry holds adds no entry.
  *held_by = place_recognition_.HeldBy(entry, match, cur->detection, cur->stereo, cur->landmark);
  keyframe_unstored_entry_.reset();
  if (*held_by) {
    VLOG(2) << "frame " << frame.id << ": its place is held by keyframe " << **held_by
            << "'s entry; not stored again";
    // One camera's estimator may refuse the loop that holds the place (ReturnLoopIds).
    if (!rig_.is_stereo() && match && match->loop.old_frame == **held_by) {
      keyframe_unstored_entry_ = std::move(entry);
    }
  } else {
    place_recognition_.Add(std::move(entry));
  }
  if (!match) return std::nullopt;
  return match->loop;
}

void Frontend::ReturnLoopIds(const LoopDetection& loop) {
  place_recognition_.LoopNotClosed();
  if (!prev_ || loop.relabelled.empty()) return;
  const std::unordered_map<LandmarkId, LandmarkId> before = IdsBeforeLoop(loop);
  const FrameId frame = prev_->id;
  const auto give_back = [&](TrackedFrame* f) {
    if (f && f->id == frame) RenameLandmarkIds(before, &f->landmark);
  };
  give_back(&*prev_);
  give_back(keyframe_ ? &*keyframe_ : nullptr);
  give_back(tracked_keyframe_ ? &*tracked_keyframe_ : nullptr);
  place_recognition_.mutable_database()->RenameLandmarks(frame, before);
  local_map_search_.RenameRemembered(frame, before);
  VLOG(1) << "frame " << frame << ": the loop to frame " << loop.old_frame << " was not closed; "
          << before.size() << " points take back their ids";
  // The refused loop had made the old keyframe the holder of this keyframe's place
  // (PlaceReleasedByRefusedLoop).
  if (keyframe_ && keyframe_->id == frame && keyframe_held_by_ == loop.old_frame &&
      keyframe_unstored_entry_ && keyframe_unstored_entry_->frame == frame) {
    RenameLandmarkIds(before, &keyframe_unstored_entry_->landmark);
    place_recognition_.Add(std::move(*keyframe_unstored_entry_));
    place_recognition_.ForgetHolder();
    keyframe_unstored_entry_.reset();
    keyframe_held_by_.reset();
  }
}

void CheckFrameSuitsRig(const Frame& frame, const StereoRig& rig) {
  const auto check = [&](const cv::Mat& image, const char* which) {
    if (image.empty()) {
      throw Error() << "frame " << frame.id.value << ": the " << which << " image is empty";
    }
    if (image.type() != CV_8UC1) {
      throw Error() << "frame " << frame.id.value << ": the " << which << " image is "
                    << cv::typeToString(image.type())
                    << "; dala takes 8-bit grey images (CV_8UC1): convert it first, e.g. "
                       "cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY)";
    }
    if (image.cols != rig.left.width || image.rows != rig.left.height) {
      throw Error() << "frame " << frame.id.value << ": the " << which << " image is " << image.cols
                    << "x" << image.rows << " pixels, the rig's calibration " << rig.left.width
                    << "x" << rig.left.height
                    << ": an image of another camera, or a calibration for another resolution";
    }
  };
  check(frame.left, "left");
  if (rig.is_stereo() && !frame.right.empty()) check(frame.right, "right");
}

void Frontend::FollowEstimator() {
  // After a relocalisation the stereo dead reckoning restarts from the estimator's pose (see
  // relocalised_prev_); the extrapolation across the gap is discarded. (One camera's dead
  // reckoning has its own unit and is only compared with itself: it goes on.)
  // Kept until the estimator has placed a frame (its PnP may succeed a frame later, on the ids
  // the relocalised frame passed on).
  if (relocalised_prev_ && prev_) {
    if (const std::optional<Pose> T_w_prev = local_map_search_.TrackedPoseAt(prev_->id)) {
      if (rig_.is_stereo()) prev_->T_w_c = *T_w_prev;
      relocalised_prev_ = false;
    }
  }
  if (awaiting_map_ && prev_ && local_map_search_.TrackedPoseAt(prev_->id)) awaiting_map_ = false;
  // The last keyframe the estimator tracked: what a lost frame is relocalised against.
  if (keyframe_ && prev_ && keyframe_->id == prev_->id && local_map_search_.has_map() &&
      !local_map_search_.LostAt(prev_->id)) {
    tracked_keyframe_ = keyframe_;
  }
}

namespace {

// The left image's interest points into *left; returns the right image's (stereo). `helper`
// (optional) detects the right image beside the left one, or helps with the left image's
// pyramid levels and descriptors for one camera.
DetectedImage DetectImages(const Frame& frame, bool stereo, const HarrisOptions& options,
                           WorkerThread* helper, DetectedImage* left) {
  DetectedImage right;
  if (stereo && helper != nullptr) {
    helper->Start([&] { right = DetectHarris(frame.right, options); });
    *left = DetectHarris(frame.left, options);
    helper->Wait();
  } else {
    *left = DetectHarris(frame.left, options, stereo ? nullptr : helper);
    if (stereo) right = DetectHarris(frame.right, options);
  }
  return right;
}

}  // namespace

FrameFeatures ComputeFrameFeatures(const Frame& frame, const StereoRig& rig,
                                   const FrontendOptions& options, WorkerThread* helper) {
  CheckFrameSuitsRig(frame, rig);
  FrameFeatures features;
  features.frame = frame.id;
  features.stereo = rig.is_stereo() && !frame.right.empty();
  auto t0 = Clock::now();
  const DetectedImage right =
      DetectImages(frame, features.stereo, options.harris,
                   options.parallel_detection ? helper : nullptr, &features.left);
  features.detect_ms = MsSince(t0);
  t0 = Clock::now();
  if (features.stereo) {
    features.stereo_points =
        MatchStereo(rig, features.left, right, frame.left, frame.right, options.stereo);
  }
  features.stereo_ms = MsSince(t0);
  return features;
}

DetectedImage Frontend::Detect(const Frame& frame, bool stereo, TrackedFrame* cur) {
  const DetectedImage right =
      DetectImages(frame, stereo, options_.harris,
                   options_.parallel_detection ? &detection_worker_ : nullptr, &cur->detection);
  StartTracks(cur);
  return right;
}

void Frontend::StartTracks(TrackedFrame* cur) {
  const size_t n = cur->detection.points.size();
  cur->landmark.assign(n, LandmarkId());
  cur->track_length.assign(n, 1);
}

bool Frontend::PredictsBesideStereo(bool stereo) const {
  return stereo && prev_ && options_.parallel_detection;
}

std::optional<std::vector<Match>> Frontend::AdoptFeatures(const FrameFeatures& features,
                                                          TrackedFrame* cur) {
  cur->detection = features.left;
  // The matcher's neighbour lists are computed on first use: each frontend its own.
  cur->detection.neighbour_cache = std::make_shared<NeighbourCache>();
  StartTracks(cur);
  cur->stereo = features.stereo ? features.stereo_points
                                : std::vector<std::optional<StereoPoint>>(
                                      cur->detection.points.size(), std::nullopt);
  // As MatchStereoAndPredict: the first tracking attempt's matches made here only where it
  // makes them beside the stereo matching (the same matches TrackFromPrevious would make).
  if (PredictsBesideStereo(features.stereo)) {
    return MatchTemporal(*prev_, cur->detection, &velocity_T_prev_cur_);
  }
  return std::nullopt;
}

std::optional<std::vector<Match>> Frontend::MatchStereoAndPredict(const Frame& frame, bool stereo,
                                                                  const DetectedImage& right,
                                                                  TrackedFrame* cur) {
  cur->stereo.assign(cur->detection.points.size(), std::nullopt);
  std::optional<std::vector<Match>> predicted_matches;
  const bool overlap = PredictsBesideStereo(stereo);
  if (overlap) {
    detection_worker_.Start(
        [&] { predicted_matches = MatchTemporal(*prev_, cur->detection, &velocity_T_prev_cur_); });
  }
  if (stereo) {
    cur->stereo = MatchStereo(rig_, cur->detection, right, frame.left, frame.right, options_.stereo);
  }
  if (overlap) detection_worker_.Wait();
  return predicted_matches;
}

std::optional<MotionEstimate> Frontend::TrackAndDeadReckon(
    TrackedFrame* cur, std::optional<std::vector<Match>> predicted_matches, TrackingStatus* status) {
  if (!prev_) {
    *status = TrackingStatus::kInitializing;
    return std::nullopt;
  }
  std::optional<MotionEstimate> motion = TrackFromPrevious(cur, std::move(predicted_matches));
  if (motion) {
    // Monocular: the essential matrix gives the direction, not the length: keep the previous
    // step's length (read before the velocity is replaced; the first step has length 1).
    // A rotation-only motion (EstimateRotation) has no translation: the step length is kept
    // for the next frame that has one.
    const double step = velocity_T_prev_cur_.translation().norm();
    if (step > 0) mono_step_length_ = step;
    velocity_T_prev_cur_ = motion->T_prev_cur;
    if (!motion->scale_known) velocity_T_prev_cur_.translation() *= mono_step_length_;
  }
  // Lost: assume the last velocity for this frame (the gap is flagged by the status).
  cur->T_w_c = Orthonormalized(prev_->T_w_c * velocity_T_prev_cur_);
  path_length_m_ += (cur->T_w_c.translation() - prev_->T_w_c.translation()).norm();
  *status = motion ? TrackingStatus::kTracking : TrackingStatus::kLost;
  return motion;
}

bool Frontend::GuidedSearchOn(FrameId frame, bool stereo, bool tracked, const TrackedFrame& cur) {
  const double auto_below = options_.local_map.stereo_when_tracked_below;
  const size_t n = cur.landmark.size();
  if (stereo && tracked && auto_below > 0 && n > 0) {
    const double continued = static_cast<double>(std::count_if(
        cur.landmark.begin(), cur.landmark.end(), [](const LandmarkId& id) { return id.valid(); }));
    const double fraction = continued / n;
    mean_tracked_fraction_ =
        mean_tracked_fraction_ < 0 ? fraction : 0.8 * mean_tracked_fraction_ + 0.2 * fraction;
    const bool was_on = stereo_search_on_;
    stereo_search_on_ = was_on ? mean_tracked_fraction_ <= auto_below + 0.1
                               : mean_tracked_fraction_ < auto_below;
    if (was_on != stereo_search_on_) {
      VLOG(1) << "frame " << frame << ": guided local-map search "
              << (stereo_search_on_ ? "on" : "off") << " (mean tracked fraction "
              << mean_tracked_fraction_ << ")";
    }
  }
  return !stereo || stereo_search_on_;
}

bool Frontend::FindLandmarks(const Frame& frame, const std::optional<MotionEstimate>& motion,
                             bool guided, bool lost_before, TrackedFrame* cur) {
  if (motion && keyframe_ && keyframe_->id != prev_->id) ReacquireFromKeyframe(cur);
  if (prev_ && guided) {
    std::optional<Pose> T_prev_cur;
    if (motion) T_prev_cur = motion->T_prev_cur;
    const int found = local_map_search_.Search(prev_->id, T_prev_cur,
                                               motion && motion->scale_known, cur->detection,
                                               &cur->landmark, &cur->track_length);
    VLOG(2) << "frame " << frame.id << ": " << found << " points found in the local map";
  }
  if (lost_before && tracked_keyframe_) RelocalizeFromKeyframe(cur);
  for (LandmarkId& id : cur->landmark) {
    if (!id.valid()) id = LandmarkId(next_landmark_++);
  }
  // The last tracked keyframe may be out of view after a long loss: then any mapped place will
  // do. Not while the window's landmarks are found around the last tracked pose: a short loss
  // recovers there (the rendered `fast` run finds 12-30 after each of its lost frames and
  // recovers; relabelling some of its points from the database too made it lose 14 more).
  if (!lost_before) return false;
  const int mapped = static_cast<int>(std::count_if(
      cur->landmark.begin(), cur->landmark.end(),
      [&](const LandmarkId& id) { return local_map_search_.IsMapped(id); }));
  return mapped < options_.loop.relocalise_below_mapped && RelocalizeFromDatabase(frame, cur);
}

bool Frontend::DecideKeyframe(const TrackedFrame& cur, bool stereo, bool guided,
                              bool relocalised, FrameMeasurement* out) {
  ++frames_since_keyframe_;
  // A relocalised frame starts again where the map is: a keyframe.
  if (!keyframe_ || out->status != TrackingStatus::kTracking || relocalised) return true;
  // The keyframe's landmarks the evidence counts: with a local map (one camera), those the
  // estimator maps, since most detections never become landmarks and would make every frame
  // a keyframe (KITTI: ~30 % of the detections are tracked to the next frame); else all.
  const bool mapped_only = local_map_search_.has_map() && guided;
  std::unordered_map<LandmarkId, Eigen::Vector2d> kf_uv;
  for (size_t i = 0; i < keyframe_->landmark.size(); ++i) {
    if (mapped_only && !local_map_search_.IsMapped(keyframe_->landmark[i])) continue;
    kf_uv[keyframe_->landmark[i]] = keyframe_->detection.points[i].uv;
  }
  std::vector<double> parallax;
  const bool unrotate = !stereo && options_.keyframe.mono_parallax_without_rotation;
  const Eigen::Matrix3d R_cur_kf =
      unrotate ? Eigen::Matrix3d(cur.T_w_c.linear().transpose() * keyframe_->T_w_c.linear())
               : Eigen::Matrix3d::Identity();
  for (size_t i = 0; i < cur.landmark.size(); ++i) {
    const auto it = kf_uv.find(cur.landmark[i]);
    if (it == kf_uv.end()) continue;
    Eigen::Vector2d from = it->second;
    if (unrotate) {
      Eigen::Vector2d rotated;
      if (rig_.left.Project(R_cur_kf * rig_.left.Unproject(it->second), &rotated)) from = rotated;
    }
    parallax.push_back((cur.detection.points[i].uv - from).norm());
  }
  KeyframeEvidence evidence;
  evidence.frames_since_keyframe = frames_since_keyframe_;
  evidence.tracked_fraction =
      kf_uv.empty() ? 0.0 : static_cast<double>(parallax.size()) / kf_uv.size();
  if (!parallax.empty()) {
    std::nth_element(parallax.begin(), parallax.begin() + parallax.size() / 2, parallax.end());
    evidence.median_parallax_px = parallax[parallax.size() / 2];
  }
  evidence.T_kf_cur = keyframe_->T_w_c.inverse() * cur.T_w_c;
  // One camera: the dead-reckoned translation has no unit, so no criterion on distance.
  if (!stereo) evidence.T_kf_cur.translation().setZero();
  evidence.stereo_baseline_m = stereo ? rig_.baseline : 0.0;
  evidence.revisiting = keyframe_held_by_.has_value();
  out->tracked_fraction = evidence.tracked_fraction;
  return keyframe_policy_.IsKeyframe(evidence);
}

void Frontend::FillObservations(const TrackedFrame& cur, FrameMeasurement* out) const {
  const size_t n = cur.landmark.size();
  out->observations.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    FeatureObservation o;
    o.landmark = cur.landmark[i];
    o.uv = cur.detection.points[i].uv;
    o.sigma_px = options_.stereo.sigma_px;
    o.track_length = cur.track_length[i];
    if (cur.stereo[i]) {
      o.u_right = cur.stereo[i]->u_right;
      o.p_c0 = cur.stereo[i]->p_c0;
      o.cov_p_c0 = cur.stereo[i]->cov_p_c0;
    }
    out->observations.push_back(o);
  }
}

FrameMeasurement Frontend::Process(const Frame& frame) { return ProcessFrame(frame, nullptr); }

FrameMeasurement Frontend::Process(const Frame& frame, const FrameFeatures& features) {
  return ProcessFrame(frame, &features);
}

FrameMeasurement Frontend::ProcessFrame(const Frame& frame, const FrameFeatures* features) {
  CheckFrameSuitsRig(frame, rig_);
  const bool stereo = rig_.is_stereo() && !frame.right.empty();
  if (features != nullptr && (features->frame != frame.id || features->stereo != stereo ||
                              features->left.image_size != frame.left.size())) {
    throw Error() << "the features given with frame " << frame.id.value << " are those of frame "
                  << features->frame.value << " (" << (features->stereo ? "stereo" : "one camera")
                  << ", " << features->left.image_size.width << "x"
                  << features->left.image_size.height
                  << "): compute them from this frame with this frontend's rig "
                     "(ComputeFrameFeatures)";
  }
  const auto t_start = Clock::now();
  FrameMeasurement out;
  out.frame = frame.id;
  out.t_ns = frame.t_ns;
  out.stereo = stereo;
  FollowEstimator();

  // 1. Interest points, both images at once.
  TrackedFrame cur;
  cur.id = frame.id;
  std::optional<std::vector<Match>> predicted_matches;
  auto t0 = Clock::now();
  if (features != nullptr) {
    // Computed already (ComputeFrameFeatures): their times are this frame's too (and in
    // total_ms below).
    out.timings.detect_ms = features->detect_ms + MsSince(t_start);
    predicted_matches = AdoptFeatures(*features, &cur);
    out.timings.stereo_ms = features->stereo_ms + MsSince(t0);
  } else {
    const DetectedImage right = Detect(frame, stereo, &cur);
    out.timings.detect_ms = MsSince(t_start);

    // 2. Stereo, and on the worker the temporal matches of the first tracking attempt
    // (predicted by the constant velocity): both only read the detections, so they run side by
    // side, with the same result as one after the other. stereo_ms is then the time of both.
    t0 = Clock::now();
    predicted_matches = MatchStereoAndPredict(frame, stereo, right, &cur);
    out.timings.stereo_ms = MsSince(t0);
  }

  // 3. Tracking and motion.
  t0 = Clock::now();
  const std::optional<MotionEstimate> motion =
      TrackAndDeadReckon(&cur, std::move(predicted_matches), &out.status);
  out.timings.motion_ms = MsSince(t0);

  // 4. The landmark of each point: the keyframe's lost tracks, the guided local-map search (one
  // camera, or stereo while the frame-to-frame tracks break), after a lost frame the
  // relocalisation, new ids for the rest.
  t0 = Clock::now();
  const bool guided = GuidedSearchOn(frame.id, stereo, motion.has_value(), cur);
  // Lost before, or not yet placed in a saved map (UseMap): from the first frame on.
  const bool lost_before = (prev_ && local_map_search_.LostAt(prev_->id)) || awaiting_map_;
  const bool relocalised = FindLandmarks(frame, motion, guided, lost_before, &cur);
  out.timings.track_ms = MsSince(t0);
  T_w_cur_ = cur.T_w_c;
  out.motion = motion;

  // 5. Keyframe decision against the last keyframe.
  out.is_keyframe = DecideKeyframe(cur, stereo, guided, relocalised, &out);

  // 6. Loop detection at keyframes (relabels the recognised points before they are output).
  // Not after a loss: the dead-reckoned pose that gates a loop is an extrapolation then, and a
  // recognised place has already relabelled the points (RelocalizeFromDatabase).
  if (out.is_keyframe && options_.loop.enable && !lost_before &&
      (stereo || (prev_ && local_map_search_.has_map()))) {
    t0 = Clock::now();
    out.loop = DetectLoop(frame, motion, &cur, &out.place_held_by);
    out.timings.loop_ms = MsSince(t0);
  }

  // 7. The measurement, and what the next frames keep of this one. Appearances are kept only
  // where the System hands over local maps (System::Track) and the search may run.
  FillObservations(cur, &out);
  if (!stereo || options_.local_map.stereo_when_tracked_below > 0) {
    local_map_search_.Remember(cur.id, cur.detection, cur.landmark, cur.track_length);
  }
  relocalised_prev_ = relocalised_prev_ || relocalised;
  if (out.is_keyframe) {
    keyframe_ = cur;
    keyframe_held_by_ = out.place_held_by;
    frames_since_keyframe_ = 0;
  }
  prev_ = std::move(cur);
  out.timings.total_ms =
      MsSince(t_start) + (features != nullptr ? features->detect_ms + features->stereo_ms : 0.0);
  return out;
}

}  // namespace dala
