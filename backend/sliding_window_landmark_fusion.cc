// SlidingWindowEstimator's side of landmark fusion (SlidingWindowBa::FuseLandmarks): the
// merged ids renamed in what the estimator keeps and in the frontend's later measurements.

#include <algorithm>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "backend/sliding_window_estimator.h"

namespace dala {

void SlidingWindowEstimator::RenameFused(
    const std::vector<std::pair<LandmarkId, LandmarkId>>& fused) {
  if (fused.empty()) return;
  // Each landmark is in one pair at most (FuseLandmarks), so one pass renames them all.
  std::map<LandmarkId, LandmarkId> survivor_of;
  std::set<LandmarkId> survivors;
  for (const auto& [loser, survivor] : fused) {
    survivor_of[loser] = survivor;
    survivors.insert(survivor);
    // Ids that had fused into the loser now lead to the survivor.
    const auto [first, last] = fused_from_.equal_range(loser);
    std::vector<LandmarkId> earlier;
    for (auto it = first; it != last; ++it) earlier.push_back(it->second);
    fused_from_.erase(loser);
    for (const LandmarkId e : earlier) {
      fused_into_[e] = survivor;
      fused_from_.emplace(survivor, e);
    }
    fused_into_[loser] = survivor;
    fused_from_.emplace(survivor, loser);

    if (const auto n = landmark_observations_.find(loser); n != landmark_observations_.end()) {
      landmark_observations_[survivor] += n->second;
      landmark_observations_.erase(n);
    }
    if (const auto a = anchor_.find(loser); a != anchor_.end()) {
      anchor_.emplace(survivor, a->second);
      anchor_.erase(a);
    }
    map_points_.erase(loser);
  }
  // A keyframe's observations by id: the loser's become the survivor's unless it has one.
  const auto rename = [&](std::map<LandmarkId, BaObservation>* seen) {
    for (const auto& [loser, survivor] : survivor_of) {
      const auto it = seen->find(loser);
      if (it == seen->end()) continue;
      BaObservation o = it->second;
      seen->erase(it);
      o.landmark = survivor;
      seen->emplace(survivor, o);
    }
  };
  rename(&last_keyframe_observations_);
  for (auto& [kf, seen] : earlier_keyframe_observations_) rename(&seen);
  for (WaitingFrame& w : waiting_frames_) {
    for (BaObservation& o : w.observations) {
      if (const auto it = survivor_of.find(o.landmark); it != survivor_of.end()) {
        o.landmark = it->second;
      }
    }
    // A frame that saw the point under both ids keeps one observation of it (the first).
    std::set<LandmarkId> kept;
    const auto is_duplicate = [&](const BaObservation& o) {
      return survivors.count(o.landmark) > 0 && !kept.insert(o.landmark).second;
    };
    w.observations.erase(std::remove_if(w.observations.begin(), w.observations.end(), is_duplicate),
                         w.observations.end());
  }
  for (auto& [kf, o] : observation_archive_) {
    if (const auto it = survivor_of.find(o.landmark); it != survivor_of.end()) {
      o.landmark = it->second;
    }
  }
}

FrameMeasurement SlidingWindowEstimator::WithFusedIds(const FrameMeasurement& m) const {
  FrameMeasurement out = m;
  std::set<LandmarkId> renamed;
  for (FeatureObservation& o : out.observations) {
    const auto it = fused_into_.find(o.landmark);
    if (it == fused_into_.end()) continue;
    o.landmark = it->second;
    renamed.insert(it->second);
  }
  if (renamed.empty()) return out;
  std::vector<FeatureObservation> kept;
  kept.reserve(out.observations.size());
  for (size_t i = 0; i < out.observations.size(); ++i) {
    const FeatureObservation& o = out.observations[i];
    const bool was_renamed = fused_into_.count(m.observations[i].landmark) > 0;
    if (!was_renamed && renamed.count(o.landmark)) continue;
    kept.push_back(o);
  }
  out.observations = std::move(kept);
  return out;
}

}  // namespace dala
