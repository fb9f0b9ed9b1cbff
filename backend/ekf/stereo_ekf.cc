#include "backend/ekf/stereo_ekf.h"

#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "backend/ekf/ekf_models.h"

namespace dala {

bool StereoEkfOptions::IsValid(std::string* why) const {
  std::ostringstream os;
  if (max_landmarks < 1) os << "max_landmarks " << max_landmarks << " must be >= 1; ";
  if (grid_cols < 1 || grid_rows < 1) os << "grid_cols/grid_rows must be >= 1; ";
  if (target_per_zone < 0 || new_per_zone_per_frame < 0) {
    os << "target_per_zone and new_per_zone_per_frame must be >= 0; ";
  }
  if (min_track_length < 1) os << "min_track_length must be >= 1; ";
  if (!(max_relative_depth_sigma > 0)) os << "max_relative_depth_sigma must be > 0; ";
  if (!(gate_chi2 > 0) || !(loop_gate_chi2 > 0)) os << "gate_chi2 and loop_gate_chi2 must be > 0; ";
  if (loop_min_gap_frames < 2) os << "loop_min_gap_frames must be >= 2; ";
  if (!(motion_covariance_scale > 0)) os << "motion_covariance_scale must be > 0; ";
  if (max_gate_failures < 1) os << "max_gate_failures must be >= 1; ";
  if (max_batch_observations < 1) os << "max_batch_observations must be >= 1; ";
  if (evict_unseen_frames < 1) os << "evict_unseen_frames must be >= 1; ";
  if (!(lost_rotation_sigma >= 0) || !(lost_translation_sigma >= 0)) {
    os << "lost_rotation_sigma and lost_translation_sigma must be >= 0; ";
  }
  if (why != nullptr) *why = os.str();
  return os.str().empty();
}

StereoEkfEstimator::StereoEkfEstimator(const StereoRig& rig, const StereoEkfOptions& options)
    : rig_(rig),
      options_(options),
      grid_(rig.left.width, rig.left.height, options.grid_cols, options.grid_rows),
      state_(options.max_landmarks) {
  std::string why;
  CHECK(options.IsValid(&why)) << "StereoEkfOptions: " << why;
  CHECK(rig.IsValid(&why)) << "StereoEkfEstimator: " << why;
  CHECK(rig.is_stereo()) << "StereoEkfEstimator needs a stereo rig (baseline > 0)";
}

bool StereoEkfEstimator::MakeBlock(int i, const FeatureObservation& obs,
                                   EkfUpdateBlock* block) const {
  Eigen::Vector3d uvd;
  Eigen::Matrix<double, 3, 6> H_pose;
  Eigen::Matrix3d H_p;
  if (!PredictStereoObservation(rig_, state_.T_w_c(), state_.p_w(i), &uvd, &H_pose, &H_p)) {
    return false;
  }
  const Eigen::Vector3d z(obs.uv.x(), obs.uv.y(), obs.disparity());
  block->residual = z - uvd;
  block->R = StereoObservationCovariance(obs.sigma_px);
  block->H_pose = H_pose;
  block->landmark = i;
  block->H_landmark = H_p;
  return true;
}

EstimatorOutput StereoEkfEstimator::Add(const FrameMeasurement& m) {
  ++frame_index_;
  stats_ = {};
  EstimatorOutput out;
  if (frame_index_ == 0) {
    state_.Reset(Pose::Identity(), Matrix6d::Zero());
    out.valid = true;
  } else if (m.motion.has_value()) {
    state_.Predict(m.motion->T_prev_cur, options_.motion_covariance_scale * m.motion->cov);
    out.valid = true;
  } else {
    Vector6d var;
    const double sr = options_.lost_rotation_sigma, st = options_.lost_translation_sigma;
    var << sr * sr, sr * sr, sr * sr, st * st, st * st, st * st;
    state_.InflatePose(var.asDiagonal());
    out.valid = false;
  }

  // Observations of landmarks in the state, split into loop re-observations and regular ones.
  // A loop re-observation is one of a landmark the frontend relabelled at a recognised place
  // (m.loop), or of a landmark unseen for loop_min_gap_frames (a tracker that keeps ids).
  std::unordered_set<LandmarkId> relabelled;
  if (m.loop.has_value()) {
    for (const auto& [current, old] : m.loop->relabelled) relabelled.insert(old);
  }
  std::vector<const FeatureObservation*> old_obs, regular_obs;
  for (const FeatureObservation& obs : m.observations) {
    if (!obs.has_stereo() || state_.IndexOf(obs.landmark) < 0) continue;
    const EkfLandmarkInfo& info = info_.at(obs.landmark);
    if (relabelled.count(obs.landmark) > 0 ||
        frame_index_ - info.last_seen >= options_.loop_min_gap_frames) {
      old_obs.push_back(&obs);
    } else {
      regular_obs.push_back(&obs);
    }
  }
  std::unordered_map<LandmarkId, Eigen::Vector2d> seen_uv;  // Applied this frame.
  auto gate = [&](const FeatureObservation& obs, double chi2, EkfUpdateBlock* block) {
    const int i = state_.IndexOf(obs.landmark);
    EkfLandmarkInfo& info = info_.at(obs.landmark);
    bool ok = MakeBlock(i, obs, block);
    if (ok) {
      const Eigen::MatrixXd S = state_.InnovationCovariance(*block);
      const Eigen::LLT<Eigen::MatrixXd> llt(S);
      ok = llt.info() == Eigen::Success && block->residual.dot(llt.solve(block->residual)) < chi2;
    }
    if (ok) {
      info.last_seen = frame_index_;
      ++info.observations;
      info.gate_failures = 0;
      seen_uv[obs.landmark] = obs.uv;
      ++stats_.updated;
    } else {
      ++info.gate_failures;
      ++stats_.gated_out;
    }
    return ok;
  };
  for (const FeatureObservation* obs : old_obs) {
    EkfUpdateBlock block;
    if (gate(*obs, options_.loop_gate_chi2, &block) && state_.Update({block})) {
      ++stats_.loop_updates;
    }
  }
  // Gated at the prior, then applied in batches of max_batch_observations, each relinearised at
  // the state corrected by the previous batches (the cost of one batch of m rows is
  // O(n m^2 + n^2 m): small batches avoid the n m^2 term of one huge batch).
  std::vector<const FeatureObservation*> accepted;
  for (const FeatureObservation* obs : regular_obs) {
    EkfUpdateBlock block;
    if (gate(*obs, options_.gate_chi2, &block)) accepted.push_back(obs);
  }
  for (size_t begin = 0; begin < accepted.size(); begin += options_.max_batch_observations) {
    const size_t end = std::min(accepted.size(), begin + options_.max_batch_observations);
    std::vector<EkfUpdateBlock> blocks;
    for (size_t k = begin; k < end; ++k) {
      EkfUpdateBlock block;
      if (MakeBlock(state_.IndexOf(accepted[k]->landmark), *accepted[k], &block)) {
        blocks.push_back(std::move(block));
      }
    }
    if (!state_.Update(blocks)) LOG(WARNING) << "StereoEkf: singular innovation, batch skipped";
  }
  out.loop_closed = stats_.loop_updates > 0;

  // Removal of unreliable landmarks.
  std::vector<bool> remove(state_.num_landmarks(), false);
  bool any = false;
  for (int i = 0; i < state_.num_landmarks(); ++i) {
    if (info_.at(state_.id(i)).gate_failures >= options_.max_gate_failures) {
      remove[i] = any = true;
      info_.erase(state_.id(i));
      rejected_.insert(state_.id(i));
      ++stats_.removed;
    }
  }
  if (any) state_.RemoveLandmarks(remove);

  // New landmarks where zones lack them.
  const int zones = grid_.size();
  std::vector<int> count(zones, 0);
  for (const auto& [id, uv] : seen_uv) ++count[grid_.Zone(uv)];
  std::vector<std::vector<const FeatureObservation*>> candidates(zones);
  for (const FeatureObservation& obs : m.observations) {
    if (!obs.has_stereo() || !(obs.disparity() > 0) || state_.IndexOf(obs.landmark) >= 0 ||
        rejected_.count(obs.landmark) > 0) {
      continue;
    }
    if (obs.track_length < options_.min_track_length || !(obs.p_c0.z() > 0)) continue;
    if (std::sqrt(obs.cov_p_c0(2, 2)) > options_.max_relative_depth_sigma * obs.p_c0.z()) continue;
    candidates[grid_.Zone(obs.uv)].push_back(&obs);
  }
  std::vector<const FeatureObservation*> to_add;
  for (int z = 0; z < zones; ++z) {
    auto& c = candidates[z];
    std::sort(c.begin(), c.end(), [](const FeatureObservation* a, const FeatureObservation* b) {
      if (a->track_length != b->track_length) return a->track_length > b->track_length;
      if (a->cov_p_c0.trace() != b->cov_p_c0.trace())
        return a->cov_p_c0.trace() < b->cov_p_c0.trace();
      return a->landmark < b->landmark;
    });
    const int n = std::min<int>({static_cast<int>(c.size()), options_.new_per_zone_per_frame,
                                 std::max(0, options_.target_per_zone - count[z])});
    to_add.insert(to_add.end(), c.begin(), c.begin() + n);
  }
  const int deficit =
      static_cast<int>(to_add.size()) - (state_.max_landmarks() - state_.num_landmarks());
  if (deficit > 0) {
    // Evict landmarks unseen for long (ekf_map.h: fewest observations, then the newest first).
    const std::vector<int> evictable =
        EvictionOrder(state_, info_, frame_index_, options_.evict_unseen_frames);
    std::vector<bool> evict(state_.num_landmarks(), false);
    const int n = std::min<int>(deficit, static_cast<int>(evictable.size()));
    for (int k = 0; k < n; ++k) {
      evict[evictable[k]] = true;
      info_.erase(state_.id(evictable[k]));
      ++stats_.removed;
    }
    if (n > 0) state_.RemoveLandmarks(evict);
  }
  for (const FeatureObservation* obs : to_add) {
    if (state_.full()) break;
    state_.AddLandmarkFromCamera(obs->landmark, obs->p_c0, obs->cov_p_c0);
    info_[obs->landmark] = EkfLandmarkInfo{frame_index_, frame_index_, 1, 0};
    ++stats_.added;
  }

  FinishEkfFrame(state_, m.t_ns, &out, &trajectory_);
  return out;
}

}  // namespace dala
