// SlidingWindowBa::FuseLandmarks (see sliding_window_ba.h, "Landmark fusion").

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include "backend/ba/reprojection_factors.h"
#include "backend/ba/sliding_window_ba.h"

namespace dala {
namespace {

// A candidate pair: the older landmark's projection in the newest keyframe lies `distance_px`
// from the newer one's observation there.
struct FusionCandidate {
  double distance_px = 0.0;
  LandmarkId projected;  // Not seen by the newest keyframe.
  LandmarkId observed;   // Seen there.
};

}  // namespace

std::vector<std::pair<LandmarkId, LandmarkId>> SlidingWindowBa::FuseLandmarks() {
  std::vector<std::pair<LandmarkId, LandmarkId>> merged;
  const double radius = options_.fuse_radius_px;
  if (radius <= 0.0 || window_.size() < 2) return merged;
  const KeyframeState& newest = window_.back();

  // Every view of every landmark, window and held keyframes.
  std::map<LandmarkId, std::vector<std::pair<const KeyframeState*, const BaObservation*>>> views;
  for (const auto* keyframes : {&held_, &window_}) {
    for (const KeyframeState& kf : *keyframes) {
      for (const BaObservation& o : kf.observations) views[o.landmark].emplace_back(&kf, &o);
    }
  }
  // The newest keyframe's observations of landmarks with a position, by pixel cell of size
  // `radius`: a projection's neighbours are in its cell and the eight around it.
  std::set<LandmarkId> in_newest;
  std::map<std::pair<int, int>, std::vector<const BaObservation*>> cells;
  const auto cell_of = [radius](const Eigen::Vector2d& uv) {
    return std::make_pair(static_cast<int>(std::floor(uv.x() / radius)),
                          static_cast<int>(std::floor(uv.y() / radius)));
  };
  for (const BaObservation& o : newest.observations) {
    in_newest.insert(o.landmark);
    if (landmarks_.count(o.landmark)) cells[cell_of(o.uv)].push_back(&o);
  }

  // Candidates: a landmark the newest keyframe does not see whose projection there falls within
  // `radius` of an observation of another landmark (the nearest).
  const Pose T_c_w = BlockToPose(newest.x).inverse();
  std::vector<FusionCandidate> candidates;
  for (const auto& [id, seen] : views) {
    if (in_newest.count(id)) continue;
    const auto position = landmarks_.find(id);
    if (position == landmarks_.end()) continue;
    const Eigen::Vector3d p_c = T_c_w * position->second;
    if (p_c.z() < options_.min_depth) continue;
    const Eigen::Vector2d uv(K_.fx * p_c.x() / p_c.z() + K_.cx, K_.fy * p_c.y() / p_c.z() + K_.cy);
    // Far outside any image (and within the cells' int range): no observation near it.
    if (!(uv.cwiseAbs().maxCoeff() < 1e6)) continue;
    const auto [cx, cy] = cell_of(uv);
    const BaObservation* nearest = nullptr;
    double nearest_distance = radius;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const auto cell = cells.find({cx + dx, cy + dy});
        if (cell == cells.end()) continue;
        for (const BaObservation* o : cell->second) {
          const double d = (o->uv - uv).norm();
          if (d <= nearest_distance) {
            nearest_distance = d;
            nearest = o;
          }
        }
      }
    }
    if (nearest) candidates.push_back({nearest_distance, id, nearest->landmark});
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const FusionCandidate& a, const FusionCandidate& b) {
              return std::tie(a.distance_px, a.projected, a.observed) <
                     std::tie(b.distance_px, b.projected, b.observed);
            });

  // A pair is one point when no keyframe sees both and one position explains every view of
  // both: triangulated from all of them, each residual passes the window's outlier test.
  std::set<LandmarkId> used;
  std::map<LandmarkId, LandmarkId> survivor_of;
  for (const FusionCandidate& c : candidates) {
    if (used.count(c.projected) || used.count(c.observed)) continue;
    const auto& a = views.at(c.projected);
    const auto& b = views.at(c.observed);
    std::set<const KeyframeState*> keyframes;
    std::vector<Pose> poses;
    std::vector<Eigen::Vector2d> uv;
    bool shared = false;
    for (const auto* side : {&a, &b}) {
      for (const auto& [kf, o] : *side) {
        shared = shared || !keyframes.insert(kf).second;
        poses.push_back(BlockToPose(kf->x));
        uv.push_back(o->uv);
      }
    }
    if (shared || poses.size() < 3) continue;
    const std::optional<Eigen::Vector3d> p_w = TriangulateViews(
        K_, poses, uv, options_.min_triangulation_parallax_deg, options_.min_depth);
    if (!p_w) continue;
    bool consistent = true;
    for (const auto* side : {&a, &b}) {
      for (const auto& [kf, o] : *side) {
        double depth = 0.0;
        const double e2 = WhitenedSquaredError(K_, *o, kf->x.data(), p_w->data(), &depth);
        const double bound = ResidualDof(K_, *o) == 3 ? kChi2Quantile95Dof3 : kChi2Quantile95Dof2;
        consistent = consistent && e2 <= bound && depth >= options_.min_depth;
      }
    }
    if (!consistent) continue;
    used.insert(c.projected);
    used.insert(c.observed);
    // The older id survives: its track is the longer-lived one, and the newer id's
    // observations join it.
    const LandmarkId survivor = std::min(c.projected, c.observed);
    const LandmarkId loser = std::max(c.projected, c.observed);
    survivor_of[loser] = survivor;
    landmarks_[survivor] = *p_w;
    merged.emplace_back(loser, survivor);
  }
  for (auto* keyframes : {&held_, &window_}) {
    for (KeyframeState& kf : *keyframes) {
      for (BaObservation& o : kf.observations) {
        const auto it = survivor_of.find(o.landmark);
        if (it != survivor_of.end()) o.landmark = it->second;
      }
    }
  }
  for (const auto& [loser, survivor] : merged) landmarks_.erase(loser);
  VLOG(2) << "keyframe " << newest.id << ": " << merged.size() << " landmarks fused of "
          << candidates.size() << " candidates";
  return merged;
}

}  // namespace dala
