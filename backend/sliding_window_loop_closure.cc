// SlidingWindowEstimator's loop closure (see the class comment in sliding_window_estimator.h):
// an SE(3) pose graph when the scale is observed (stereo), a Sim(3) one with one camera.
#include <glog/logging.h>

#include <iomanip>
#include <set>
#include <sstream>
#include <string>

#include "backend/mono/loop_sim3.h"
#include "backend/mono/loop_turn_gate.h"
#include "backend/sliding_window_estimator.h"

namespace dala {
namespace {

// Information matrices of the pose-graph edges ([rotation; translation], core/geometry.h; the
// Sim(3) ones add the log scale).
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
  static Matrix7d WithScale(const Matrix6d& information, double sigma_log_scale) {
    Matrix7d out = Matrix7d::Zero();
    out.topLeftCorner<6, 6>() = information;
    out(6, 6) = 1.0 / (sigma_log_scale * sigma_log_scale);
    return out;
  }
};

}  // namespace

bool SlidingWindowEstimator::CloseLoop(const LoopDetection& loop, KeyframeId cur_id, Pose* T_w_c,
                                       std::string* why_not) {
  const auto old = keyframe_of_frame_.find(loop.old_frame);
  if (old == keyframe_of_frame_.end()) {
    *why_not = "the old frame is not a keyframe of the map";
    LOG(WARNING) << "loop to frame " << loop.old_frame << ", which is not a keyframe: ignored";
    return false;
  }
  // Nodes: every keyframe at its current estimate, and the new one.
  std::map<KeyframeId, Pose> T_w_kf;
  for (const auto& [id, pose] : keyframe_poses_) T_w_kf[id] = KeyframePoseNow(id);
  T_w_kf[cur_id] = *T_w_c;
  const LoopClosureInformation info = {options_.loop};
  std::vector<PoseGraphEdge> edges;
  for (const auto& [from, to] : ConsecutiveEdges(T_w_kf)) {
    PoseGraphEdge e;
    e.from = from;
    e.to = to;
    e.T_from_to = T_w_kf.at(from).inverse() * T_w_kf.at(to);
    e.information = info.Odometry(e.T_from_to);
    edges.push_back(e);
  }
  if (VLOG_IS_ON(1)) {
    // How far the loop moves the current keyframe from the dead reckoning: T_dr^-1 T_loop
    // (both T_old_cur), in the dead-reckoned current camera's frame.
    const Pose T_old_cur_dr = T_w_kf.at(old->second).inverse() * *T_w_c;
    const Pose correction = T_old_cur_dr.inverse() * loop.T_old_cur;
    VLOG(1) << "loop to frame " << loop.old_frame << ": measured "
            << loop.T_old_cur.translation().norm() << " m apart, dead reckoning "
            << T_old_cur_dr.translation().norm() << " m; the loop moves it "
            << correction.translation().norm() << " m and "
            << Eigen::AngleAxisd(correction.rotation()).angle() * 180.0 / M_PI << " deg";
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
    *why_not = "the pose graph's solve failed";
    LOG(WARNING) << "loop pose graph failed: loop to frame " << loop.old_frame << " ignored";
    return false;
  }
  loop_edges_.push_back(loop_edge);
  ++loops_closed_;
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

LoopTurn SlidingWindowEstimator::MonoLoopTurn(KeyframeId old, const Pose& T_w_c,
                                              const Pose& T_w_c_loop, FrameId old_frame) const {
  const double path = KeyframePathFrom(keyframe_poses_, old, T_w_c.translation());
  LoopTurn turn =
      CheckLoopTurn(T_w_c.rotation(), T_w_c_loop.rotation(), path,
                    options_.loop.mono_max_turn_deg, options_.loop.mono_max_turn_deg_per_unit);
  if (!options_.loop.mono_turn_gate) turn.within = true;
  if (!turn.within) {
    VLOG(1) << "loop to frame " << old_frame << ": it would turn the camera by " << turn.turn_deg
            << " deg, more than the gate's " << turn.max_deg << " deg after " << path
            << " map units: ignored";
  }
  return turn;
}

bool SlidingWindowEstimator::CloseMonoLoop(const FrameMeasurement& m, KeyframeId cur_id,
                                           Pose* T_w_c, std::string* why_not) {
  const LoopDetection& loop = *m.loop;
  const auto old = keyframe_of_frame_.find(loop.old_frame);
  if (old == keyframe_of_frame_.end()) {
    *why_not = "the old frame is not a keyframe of the map";
    LOG(WARNING) << "loop to frame " << loop.old_frame << ", which is not a keyframe: ignored";
    return false;
  }
  // The recognised landmarks with an estimate on both sides: where the current neighbourhood
  // puts them, and where the old one does.
  std::vector<Eigen::Vector3d> p_cur, p_old;
  for (const auto& [cur, old_id] : loop.relabelled) {
    const std::optional<Eigen::Vector3d> a = ba_.LandmarkPosition(cur);
    const std::optional<Eigen::Vector3d> b = ba_.LandmarkPosition(old_id);
    if (!a || !b) continue;
    p_cur.push_back(*a);
    p_old.push_back(*b);
  }
  const std::optional<LoopSim3> sim3 =
      EstimateLoopSim3(p_cur, p_old, T_w_c->translation(), options_.loop.sim3);
  // The current keyframe in the old neighbourhood: its pose by PnP on the old landmarks (image
  // residuals: more accurate than the similarity's rotation from noisy monocular depths), its
  // scale from the similarity (else left to the graph); the similarity alone without a PnP.
  std::set<LandmarkId> old_ids;
  for (const auto& ids : loop.relabelled) old_ids.insert(ids.second);
  const std::optional<Pose> T_w_cur_old = PnpPose(
      m, [&](LandmarkId id) { return old_ids.count(id) > 0; }, options_.loop.mono_pnp_min_inliers);
  if (!sim3 && !T_w_cur_old) {
    *why_not = "no similarity from the " + std::to_string(p_cur.size()) +
               " recognised landmarks mapped on both sides, no PnP pose on the old landmarks";
    VLOG(1) << "loop to frame " << loop.old_frame << ": " << *why_not << ": ignored";
    return false;
  }
  Sim3 S_w_cur_in_old = sim3 ? sim3->S_old_cur * Sim3{*T_w_c, 1.0} : Sim3{*T_w_cur_old, 1.0};
  if (T_w_cur_old) S_w_cur_in_old.T = *T_w_cur_old;
  const LoopTurn turn = MonoLoopTurn(old->second, *T_w_c, S_w_cur_in_old.T, loop.old_frame);
  if (!turn.within) {
    std::ostringstream why;
    why << "it would turn the camera by " << std::setprecision(3) << turn.turn_deg
        << " deg, more than the gate's " << turn.max_deg
        << " deg (loop.gate_rotation_deg, loop.gate_rotation_deg_per_m)";
    *why_not = why.str();
    return false;
  }
  const double loop_scale_sigma =
      sim3 ? options_.loop.mono_loop_scale_sigma : options_.loop.mono_pnp_scale_sigma;
  // Nodes at the current estimates, scale 1 (the map's unit everywhere).
  std::map<KeyframeId, Sim3> S_w_kf;
  for (const auto& [id, pose] : keyframe_poses_) S_w_kf[id] = Sim3{KeyframePoseNow(id), 1.0};
  S_w_kf[cur_id] = Sim3{*T_w_c, 1.0};
  const LoopClosureInformation info = {options_.loop};
  std::vector<Sim3Edge> edges;
  for (const auto& [from, to] : ConsecutiveEdges(S_w_kf)) {
    Sim3Edge e;
    e.from = from;
    e.to = to;
    e.S_from_to = S_w_kf.at(from).Inverse() * S_w_kf.at(to);
    e.information = info.WithScale(info.Odometry(e.S_from_to.T), options_.loop.mono_scale_sigma);
    edges.push_back(e);
  }
  // The loop: the current keyframe moved into the old neighbourhood by the similarity.
  Sim3Edge loop_edge;
  loop_edge.from = old->second;
  loop_edge.to = cur_id;
  loop_edge.S_from_to = S_w_kf.at(old->second).Inverse() * S_w_cur_in_old;
  loop_edge.information = info.WithScale(info.Loop(Matrix6d::Zero()), loop_scale_sigma);
  loop_edge.is_loop = true;
  edges.insert(edges.end(), mono_loop_edges_.begin(), mono_loop_edges_.end());
  edges.push_back(loop_edge);
  PoseGraphSummary summary;
  const std::map<KeyframeId, Sim3> corrected =
      OptimizeSim3PoseGraph(S_w_kf, edges, options_.loop.pose_graph, &summary);
  if (!summary.usable) {
    *why_not = "the Sim(3) pose graph's solve failed";
    LOG(WARNING) << "loop Sim(3) pose graph failed: loop to frame " << loop.old_frame << " ignored";
    return false;
  }
  VLOG(1) << "mono loop closed: keyframe " << loop_edge.from << " (frame " << loop.old_frame
          << ") -> new keyframe " << cur_id << " by "
          << (T_w_cur_old ? "PnP on the old landmarks" : "the similarity")
          << (sim3 ? ", scale from " + std::to_string(sim3->inliers) + " landmarks"
                   : std::string(", scale free"))
          << ", turning the camera by " << turn.turn_deg << " deg (gate " << turn.max_deg
          << "), pose graph cost " << summary.initial_cost << " -> " << summary.final_cost
          << ", current scale " << corrected.at(cur_id).scale;
  // Every keyframe k's unit becomes the world's again: its camera coordinates grow by s_k
  // (p_k' = s_k p_k), so a stored loop edge a -> b is re-expressed as
  //   S_a_b' = (R, s_a t, s s_a / s_b).
  mono_loop_edges_.push_back(loop_edge);
  ++loops_closed_;
  for (Sim3Edge& e : mono_loop_edges_) {
    const double s_a = corrected.at(e.from).scale, s_b = corrected.at(e.to).scale;
    e.S_from_to.T.translation() *= s_a;
    e.S_from_to.scale *= s_a / s_b;
  }
  // Landmarks move with their anchor keyframe: p_w' = S_w_a' S_w_a^-1 p_w.
  for (const auto& [id, a] : anchor_) {
    const Sim3 delta = corrected.at(a) * S_w_kf.at(a).Inverse();
    if (const auto p_w = ba_.LandmarkPosition(id)) ba_.SetLandmarkPosition(id, delta * *p_w);
    const auto it = map_points_.find(id);
    if (it != map_points_.end()) it->second = delta * it->second;
  }
  // Frames between keyframes are stored in their keyframe's unit: scaled with it.
  for (FrameRecord& f : frames_) {
    if (f.has_pose) f.T_kf_c.translation() *= corrected.at(f.reference).scale;
  }
  std::map<KeyframeId, Pose> T_w_kf;
  for (const auto& [id, S] : corrected) T_w_kf[id] = S.T;
  for (auto& [id, pose] : keyframe_poses_) pose = T_w_kf.at(id);
  ba_.ApplyCorrection(T_w_kf);
  // The previous frame's corrected pose: Add derives the velocity from it and *T_w_c.
  if (!frames_.empty() && frames_.back().has_pose) {
    T_w_prev_ = KeyframePoseNow(frames_.back().reference) * frames_.back().T_kf_c;
  }
  *T_w_c = T_w_kf.at(cur_id);
  return true;
}

void SlidingWindowEstimator::MergeIntoHolder(KeyframeId culled, KeyframeId holder) {
  const Pose T_holder_culled = keyframe_poses_.at(holder).inverse() * keyframe_poses_.at(culled);
  const Sim3 S_holder_culled{T_holder_culled, 1.0};
  // Its edges: from the keyframe before it (made order; culled ones stand for their holder),
  // kept as a measured edge to the holder unless the two are the same node or neighbours in
  // the made order (their consecutive edge says it already).
  const KeyframeId before = GraphPredecessor(culled);
  const bool adjacent = before.value + 1 == holder.value || holder.value + 1 == before.value;
  if (before.valid() && before != holder && !adjacent && keyframe_poses_.count(before)) {
    const LoopClosureInformation info{options_.loop};
    const Pose T_before_holder = keyframe_poses_.at(before).inverse() * keyframe_poses_.at(holder);
    if (rig_.is_stereo()) {
      loop_edges_.push_back(
          {before, holder, T_before_holder, info.Odometry(T_before_holder), /*is_loop=*/false});
    } else {
      mono_loop_edges_.push_back(
          {before, holder, Sim3{T_before_holder, 1.0},
           info.WithScale(info.Odometry(T_before_holder), options_.loop.mono_scale_sigma),
           /*is_loop=*/false});
    }
  }
  // Loops (and edges of earlier culls) that ended at it end at the holder now.
  for (PoseGraphEdge& e : loop_edges_) {
    if (e.from == culled)
      e = {holder, e.to, T_holder_culled * e.T_from_to, e.information, e.is_loop};
    if (e.to == culled)
      e = {e.from, holder, e.T_from_to * T_holder_culled.inverse(), e.information, e.is_loop};
  }
  for (Sim3Edge& e : mono_loop_edges_) {
    if (e.from == culled)
      e = {holder, e.to, S_holder_culled * e.S_from_to, e.information, e.is_loop};
    if (e.to == culled)
      e = {e.from, holder, e.S_from_to * S_holder_culled.Inverse(), e.information, e.is_loop};
  }
  const auto self = [](const auto& e) { return e.from == e.to; };
  loop_edges_.erase(std::remove_if(loop_edges_.begin(), loop_edges_.end(), self),
                    loop_edges_.end());
  mono_loop_edges_.erase(std::remove_if(mono_loop_edges_.begin(), mono_loop_edges_.end(), self),
                         mono_loop_edges_.end());
  merged_into_[culled] = holder;
}

KeyframeId SlidingWindowEstimator::GraphPredecessor(KeyframeId k) const {
  const KeyframeId before(k.value - 1);
  const auto merged = merged_into_.find(before);
  return merged == merged_into_.end() ? before : merged->second;
}

template <typename Node>
std::vector<std::pair<KeyframeId, KeyframeId>> SlidingWindowEstimator::ConsecutiveEdges(
    const std::map<KeyframeId, Node>& nodes) const {
  std::vector<std::pair<KeyframeId, KeyframeId>> out;
  for (auto it = nodes.begin(); it != nodes.end(); ++it) {
    if (it == nodes.begin()) continue;
    // The keyframe made before it, or the holder it was merged into (see the class comment,
    // "Culling"); the previous node when that one is unknown (never made: a new map's first).
    KeyframeId from = GraphPredecessor(it->first);
    if (!nodes.count(from)) from = std::prev(it)->first;
    if (from != it->first) out.emplace_back(from, it->first);
  }
  return out;
}

}  // namespace dala
