#include "backend/sliding_window_estimator.h"

#include <glog/logging.h>

#include <algorithm>

namespace dala {

SlidingWindowBa::Options SequenceBaOptions() {
  SlidingWindowBa::Options options;
  options.use_marginalization = true;
  options.landmark_exit = SlidingWindowBa::LandmarkExit::kDropSharedObservations;
  return options;
}

bool BaLoopClosureOptions::IsValid(std::string* why) const {
  if (!pose_graph.IsValid(why)) return false;
  if (!(rot_sigma0 > 0 && trans_sigma0 > 0 && rot_sigma_per_m >= 0 && trans_sigma_per_m >= 0 &&
        loop_min_sigma_rot > 0 && loop_min_sigma_trans > 0)) {
    if (why) *why = "loop edge sigmas must be > 0 (the per-metre ones >= 0)";
    return false;
  }
  return true;
}

bool SlidingWindowEstimatorOptions::IsValid(std::string* why) const {
  if (!ba.IsValid(why) || !loop.IsValid(why)) return false;
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

// Information matrices of the pose-graph edges ([rotation; translation], core/geometry.h).
struct LoopClosureInformation {
  BaLoopClosureOptions o;
  Matrix6d Odometry(const Pose& T_a_b) const {
    const double d = T_a_b.translation().norm();
    return Diagonal(o.rot_sigma0 + o.rot_sigma_per_m * d, o.trans_sigma0 + o.trans_sigma_per_m * d);
  }
  Matrix6d Loop(const Matrix6d& cov) const {
    Matrix6d floored = 0.5 * (cov + cov.transpose());
    for (int i = 0; i < 6; ++i) {
      const double floor = i < 3 ? o.loop_min_sigma_rot : o.loop_min_sigma_trans;
      floored(i, i) += floor * floor;
    }
    return floored.inverse();
  }
  static Matrix6d Diagonal(double sigma_rot, double sigma_trans) {
    Vector6d d;
    d << Eigen::Vector3d::Constant(1 / (sigma_rot * sigma_rot)),
        Eigen::Vector3d::Constant(1 / (sigma_trans * sigma_trans));
    return d.asDiagonal();
  }
};

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
    anchor_.emplace(o->landmark, KeyframeId(num_keyframes_ - 1));
  }
  for (const BaObservation& b : out) ++landmark_observations_[b.landmark];
  return out;
}

bool SlidingWindowEstimator::CloseLoop(const LoopDetection& loop, KeyframeId cur_id,
                                       Pose* T_w_c) {
  const auto old = keyframe_of_frame_.find(loop.old_frame);
  if (old == keyframe_of_frame_.end()) {
    LOG(WARNING) << "loop to frame " << loop.old_frame << ", which is not a keyframe: ignored";
    return false;
  }
  // Nodes: every keyframe at its current estimate, and the new one.
  std::map<KeyframeId, Pose> T_w_kf;
  for (const auto& [id, pose] : keyframe_poses_) T_w_kf[id] = KeyframePoseNow(id);
  T_w_kf[cur_id] = *T_w_c;
  const LoopClosureInformation info = {options_.loop};
  std::vector<PoseGraphEdge> edges;
  for (auto it = T_w_kf.begin(); std::next(it) != T_w_kf.end(); ++it) {
    const auto next = std::next(it);
    PoseGraphEdge e;
    e.from = it->first;
    e.to = next->first;
    e.T_from_to = it->second.inverse() * next->second;
    e.information = info.Odometry(e.T_from_to);
    edges.push_back(e);
  }
  PoseGraphEdge loop_edge;
  loop_edge.from = old->second;
  loop_edge.to = cur_id;
  loop_edge.T_from_to = loop.T_old_cur;
  loop_edge.information = info.Loop(loop.cov);
  loop_edge.is_loop = true;
  edges.insert(edges.end(), loop_edges_.begin(), loop_edges_.end());
  edges.push_back(loop_edge);
  PoseGraphSummary summary;
  const std::map<KeyframeId, Pose> corrected =
      OptimizePoseGraph(T_w_kf, edges, options_.loop.pose_graph, &summary);
  if (!summary.usable) {
    LOG(WARNING) << "loop pose graph failed: loop to frame " << loop.old_frame << " ignored";
    return false;
  }
  loop_edges_.push_back(loop_edge);
  VLOG(1) << "loop closed: keyframe " << loop_edge.from << " (frame " << loop.old_frame
          << ") -> new keyframe " << cur_id << ", " << loop.inliers << " inliers, pose graph cost "
          << summary.initial_cost << " -> " << summary.final_cost << ", current moved by "
          << (corrected.at(cur_id).translation() - T_w_c->translation()).norm() << " m";
  // Landmarks move with their anchor keyframe: p_w_new = T_w_a_new T_w_a_old^-1 p_w_old.
  for (const auto& [id, a] : anchor_) {
    const Pose delta = corrected.at(a) * T_w_kf.at(a).inverse();
    if (const auto p_w = ba_.LandmarkPosition(id)) ba_.SetLandmarkPosition(id, delta * *p_w);
    const auto it = map_points_.find(id);
    if (it != map_points_.end()) it->second = delta * it->second;
  }
  for (auto& [id, pose] : keyframe_poses_) pose = corrected.at(id);
  ba_.ApplyCorrection(corrected);
  *T_w_c = corrected.at(cur_id);
  return true;
}

Pose SlidingWindowEstimator::KeyframePoseNow(KeyframeId id) const {
  if (const auto pose = ba_.KeyframePose(id)) return *pose;
  const auto it = keyframe_poses_.find(id);
  CHECK(it != keyframe_poses_.end()) << "unknown keyframe " << id;
  return it->second;
}

void SlidingWindowEstimator::SolveWindow(KeyframeId id) {
  const SlidingWindowBa::Summary summary = ba_.Optimize();
  VLOG(2) << "keyframe " << id << ": " << summary.BriefReport();
  if (!summary.usable) LOG(WARNING) << "keyframe " << id << ": window solve not usable";
  for (const auto& [landmark, p_w] : ba_.Landmarks()) map_points_[landmark] = p_w;
  // Every keyframe's latest estimate (window ones move, the others keep their exit value).
  for (const KeyframeId k : ba_.WindowKeyframes()) keyframe_poses_[k] = *ba_.KeyframePose(k);
}

EstimatorOutput SlidingWindowEstimator::Add(const FrameMeasurement& m) {
  WaitForWindowSolve();
  if (solved_in_background_) {
    T_w_prev_ = keyframe_poses_.at(*solved_in_background_);
    solved_in_background_.reset();
  }
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
    if (m.loop && options_.loop.enable && !first) {
      out.loop_closed = CloseLoop(*m.loop, KeyframeId(num_keyframes_), &T_w_c);
    }
    if (!first) {
      // Refine the guess against the window before the keyframe joins it.
      const PoseOnlyResult r = ba_.TrackFrame(WindowObservations(m), T_w_c, options_.pose_only);
      if (r.status == PoseOnlyStatus::kOk) {
        T_w_c = r.T_w_c;
        out.valid = true;
      }
    }
    BaKeyframe kf;
    kf.id = KeyframeId(num_keyframes_++);
    kf.t_ns = m.t_ns;
    kf.T_w_c = T_w_c;
    kf.observations = SelectKeyframeObservations(m, T_w_c);
    ba_.AddKeyframe(kf);
    keyframe_poses_[kf.id] = T_w_c;
    frames_.push_back({m.t_ns, kf.id, Pose::Identity()});
    keyframe_of_frame_[m.frame] = kf.id;
    out.landmarks_in_state = static_cast<int>(ba_.Landmarks().size());
    if (options_.background_solve) {
      solved_in_background_ = kf.id;
      solver_.Start([this, id = kf.id] { SolveWindow(id); });
    } else {
      SolveWindow(kf.id);
      T_w_c = keyframe_poses_.at(kf.id);
    }
  } else {
    const KeyframeId ref(num_keyframes_ - 1);
    frames_.push_back({m.t_ns, ref, KeyframePoseNow(ref).inverse() * T_w_c});
    out.landmarks_in_state = static_cast<int>(ba_.Landmarks().size());
  }
  T_w_prev_ = T_w_c;
  out.T_w_c = T_w_c;
  return out;
}

Trajectory SlidingWindowEstimator::trajectory() const {
  WaitForWindowSolve();
  Trajectory t;
  t.poses.reserve(frames_.size());
  for (const FrameRecord& f : frames_) t.Add(f.t_ns, KeyframePoseNow(f.reference) * f.T_kf_c);
  return t;
}

std::vector<MapPoint> SlidingWindowEstimator::map() const {
  WaitForWindowSolve();
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
