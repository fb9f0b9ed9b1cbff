#include "backend/sliding_window_estimator.h"

#include <glog/logging.h>

#include <algorithm>

namespace dala {

SlidingWindowBa::Options SequenceBaOptions() {
  SlidingWindowBa::Options options;
  options.use_marginalization = false;
  // When the prior is turned on: the best variant on rendered and KITTI sequences (issue 4).
  options.landmark_exit = SlidingWindowBa::LandmarkExit::kMarginalizeAll;
  return options;
}

bool SlidingWindowEstimatorOptions::IsValid(std::string* why) const {
  if (!ba.IsValid(why)) return false;
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (max_new_landmarks_per_keyframe < 10)
    return fail("ba.max_new_landmarks_per_keyframe must be >= 10");
  if (grid_cols < 1 || grid_rows < 1) return fail("ba.grid_cols and ba.grid_rows must be >= 1");
  if (max_landmark_depth_m <= 0) return fail("ba.max_landmark_depth_m must be > 0");
  return true;
}

namespace {
StereoIntrinsics IntrinsicsOf(const StereoRig& rig) {
  StereoIntrinsics K;
  K.fx = rig.left.fx;
  K.fy = rig.left.fy;
  K.cx = rig.left.cx;
  K.cy = rig.left.cy;
  K.baseline = rig.baseline;
  return K;
}

BaObservation ToBa(const FeatureObservation& o) {
  BaObservation b;
  b.landmark = o.landmark;
  b.uv = o.uv;
  b.u_right = o.u_right;
  b.sigma_px = o.sigma_px;
  return b;
}
}  // namespace

SlidingWindowEstimator::SlidingWindowEstimator(const StereoRig& rig,
                                               const SlidingWindowEstimatorOptions& options)
    : rig_(rig), options_(options), ba_(IntrinsicsOf(rig), options.ba) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
  CHECK(rig_.is_stereo()) << "SlidingWindowEstimator needs a stereo rig (mono BA is not built)";
}

std::vector<BaObservation> SlidingWindowEstimator::WindowObservations(
    const FrameMeasurement& m) const {
  std::vector<BaObservation> out;
  for (const FeatureObservation& o : m.observations) {
    if (ba_.LandmarkPosition(o.landmark)) out.push_back(ToBa(o));
  }
  return out;
}

std::vector<BaObservation> SlidingWindowEstimator::SelectKeyframeObservations(
    const FrameMeasurement& m, const Pose& T_w_c) {
  // Landmarks the window knows always come in; new stereo landmarks fill a grid of cells,
  // longest tracks first, up to the per-keyframe budget.
  std::vector<BaObservation> out;
  std::vector<const FeatureObservation*> fresh;
  std::vector<int> cell_count(options_.grid_cols * options_.grid_rows, 0);
  const auto cell_of = [&](const Eigen::Vector2d& uv) {
    const int cx = std::clamp(static_cast<int>(uv.x() * options_.grid_cols / rig_.left.width), 0,
                              options_.grid_cols - 1);
    const int cy = std::clamp(static_cast<int>(uv.y() * options_.grid_rows / rig_.left.height),
                              0, options_.grid_rows - 1);
    return cy * options_.grid_cols + cx;
  };
  for (const FeatureObservation& o : m.observations) {
    if (landmark_observations_.count(o.landmark)) {
      out.push_back(ToBa(o));
      ++cell_count[cell_of(o.uv)];
    } else if (o.has_stereo() && o.p_c0.z() < options_.max_landmark_depth_m) {
      fresh.push_back(&o);
    }
  }
  std::stable_sort(fresh.begin(), fresh.end(),
                   [](const FeatureObservation* a, const FeatureObservation* b) {
                     return a->track_length > b->track_length;
                   });
  const int per_cell = std::max(
      1, options_.max_new_landmarks_per_keyframe / (options_.grid_cols * options_.grid_rows) + 1);
  int added = 0;
  for (const FeatureObservation* o : fresh) {
    if (added >= options_.max_new_landmarks_per_keyframe) break;
    int& n = cell_count[cell_of(o->uv)];
    if (n >= per_cell + 2) continue;
    ++n;
    ++added;
    out.push_back(ToBa(*o));
    ba_.SetLandmarkPosition(o->landmark, T_w_c * o->p_c0);
  }
  for (const BaObservation& b : out) ++landmark_observations_[b.landmark];
  return out;
}

Pose SlidingWindowEstimator::KeyframePoseNow(KeyframeId id) const {
  if (const auto pose = ba_.KeyframePose(id)) return *pose;
  const auto it = keyframe_poses_.find(id);
  CHECK(it != keyframe_poses_.end()) << "unknown keyframe " << id;
  return it->second;
}

EstimatorOutput SlidingWindowEstimator::Add(const FrameMeasurement& m) {
  EstimatorOutput out;
  // Initial guess: the previous estimate moved by the visual motion (or the last velocity).
  const bool first = frames_.empty();
  if (!first && m.motion) velocity_ = m.motion->T_prev_cur;
  Pose T_w_c = first ? Pose::Identity() : Orthonormalized(T_w_prev_ * velocity_);
  out.valid = first || m.motion.has_value();

  if (!first && !m.is_keyframe) {
    const PoseOnlyResult r = ba_.TrackFrame(WindowObservations(m), T_w_c, options_.pose_only);
    if (r.status == PoseOnlyStatus::kOk) {
      T_w_c = r.T_w_c;
      out.valid = true;
    }
  }
  if (first || m.is_keyframe) {
    if (!first) {
      // Refine the guess against the window before the keyframe joins it.
      const PoseOnlyResult r = ba_.TrackFrame(WindowObservations(m), T_w_c, options_.pose_only);
      if (r.status == PoseOnlyStatus::kOk) T_w_c = r.T_w_c;
    }
    BaKeyframe kf;
    kf.id = KeyframeId(num_keyframes_++);
    kf.t_ns = m.t_ns;
    kf.T_w_c = T_w_c;
    kf.observations = SelectKeyframeObservations(m, T_w_c);
    ba_.AddKeyframe(kf);
    const SlidingWindowBa::Summary summary = ba_.Optimize();
    if (summary.usable) out.valid = true;
    for (const auto& [id, p_w] : ba_.Landmarks()) map_points_[id] = p_w;
    // Every keyframe's latest estimate (window ones move, the others keep their exit value).
    for (const KeyframeId id : ba_.WindowKeyframes()) keyframe_poses_[id] = *ba_.KeyframePose(id);
    keyframe_poses_[kf.id] = KeyframePoseNow(kf.id);
    T_w_c = keyframe_poses_[kf.id];
    frames_.push_back({m.t_ns, kf.id, Pose::Identity()});
  } else {
    const KeyframeId ref(num_keyframes_ - 1);
    frames_.push_back({m.t_ns, ref, KeyframePoseNow(ref).inverse() * T_w_c});
  }
  T_w_prev_ = T_w_c;
  out.T_w_c = T_w_c;
  out.landmarks_in_state = static_cast<int>(ba_.Landmarks().size());
  return out;
}

Trajectory SlidingWindowEstimator::trajectory() const {
  Trajectory t;
  t.poses.reserve(frames_.size());
  for (const FrameRecord& f : frames_) t.Add(f.t_ns, KeyframePoseNow(f.reference) * f.T_kf_c);
  return t;
}

std::vector<MapPoint> SlidingWindowEstimator::map() const {
  std::vector<MapPoint> points;
  for (const auto& [id, p_w] : map_points_) {
    MapPoint p;
    p.id = id;
    p.p_w = p_w;
    const auto it = landmark_observations_.find(id);
    p.observations = it == landmark_observations_.end() ? 0 : it->second;
    points.push_back(p);
  }
  return points;
}

}  // namespace dala
