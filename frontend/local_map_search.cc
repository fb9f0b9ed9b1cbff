#include "frontend/local_map_search.h"

#include <glog/logging.h>

#include <algorithm>
#include <unordered_set>

namespace dala {

bool LocalMapSearchOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(radius_px > 0)) return fail("frontend.local_map_radius_px must be > 0");
  if (forget_after_frames < 1) return fail("frontend.local_map_forget_after_frames must be >= 1");
  if (!(stereo_when_tracked_below >= 0 && stereo_when_tracked_below <= 0.9)) {
    return fail("frontend.local_map_search_stereo_when_tracked_below must be in [0, 0.9]");
  }
  return true;
}

LocalMapSearch::LocalMapSearch(const PinholeCamera& camera, const LocalMapSearchOptions& options,
                               const MatcherOptions& matcher, bool stereo)
    : camera_(camera),
      options_(options),
      matcher_(matcher),
      forget_after_frames_(stereo ? 1 : options.forget_after_frames) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
}

void LocalMapSearch::SetLocalMap(LocalMap map) {
  // The velocity of the estimator's last two poses, when they are consecutive frames.
  if (previous_estimate_ && previous_estimate_->first.value + 1 == map.frame.value) {
    velocity_ = previous_estimate_->second.inverse() * map.T_w_c;
  } else {
    velocity_ = Pose::Identity();
  }
  if (previous_estimate_ && map.tracked) {
    path_length_ += (map.T_w_c.translation() - previous_estimate_->second.translation()).norm();
  }
  previous_estimate_ = std::make_pair(map.frame, map.T_w_c);
  map_ = std::move(map);
  point_of_.clear();
  for (const auto& [id, p_w] : map_->points) point_of_.emplace(id, p_w);
}

Pose LocalMapSearch::PredictPose(const std::optional<Pose>& T_prev_cur, bool metric) const {
  CHECK(map_.has_value());
  Pose velocity = velocity_;
  if (T_prev_cur) {
    velocity.linear() = T_prev_cur->linear();
    if (metric) velocity.translation() = T_prev_cur->translation();
  }
  return Orthonormalized(map_->T_w_c * velocity);
}

std::optional<LocalMapSearch::MappedPoints> LocalMapSearch::MappedPointsInCamera(
    FrameId previous_frame, const std::optional<Pose>& T_prev_cur,
    const std::vector<LandmarkId>& landmark) const {
  if (!options_.enable || !map_ || map_->frame != previous_frame || !map_->tracked) {
    return std::nullopt;
  }
  MappedPoints out;
  out.T_w_c = PredictPose(T_prev_cur, /*metric=*/false);
  out.path_length = path_length_;
  out.points.assign(landmark.size(), std::nullopt);
  const Pose T_c_w = out.T_w_c.inverse();
  for (size_t i = 0; i < landmark.size(); ++i) {
    const auto it = point_of_.find(landmark[i]);
    if (it == point_of_.end()) continue;
    const Eigen::Vector3d p_c = T_c_w * it->second;
    if (p_c.z() <= 0) continue;
    StereoPoint p;
    p.p_c0 = p_c;
    out.points[i] = p;
  }
  return out;
}

std::optional<LocalMapSearch::Prediction> LocalMapSearch::PredictFromMap(
    FrameId previous_frame, const std::vector<LandmarkId>& landmark,
    const DetectedImage& previous, int min_points) const {
  if (!options_.enable || !map_ || map_->frame != previous_frame) return std::nullopt;
  const Pose T_c_w = map_->T_w_c.inverse();
  Prediction out;
  out.T_prev_cur = velocity_;
  out.p_prev.assign(landmark.size(), std::nullopt);
  out.mapped.assign(landmark.size(), false);
  std::vector<double> depths;
  for (size_t i = 0; i < landmark.size(); ++i) {
    const auto it = point_of_.find(landmark[i]);
    if (it == point_of_.end()) continue;
    const Eigen::Vector3d p_c = T_c_w * it->second;
    if (p_c.z() <= 0) continue;
    out.p_prev[i] = p_c;
    out.mapped[i] = true;
    depths.push_back(p_c.z());
  }
  if (static_cast<int>(depths.size()) < min_points) return std::nullopt;
  out.num_mapped = static_cast<int>(depths.size());
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double median_depth = depths[depths.size() / 2];
  for (size_t i = 0; i < landmark.size(); ++i) {
    if (!out.p_prev[i]) out.p_prev[i] = camera_.Unproject(previous.points[i].uv) * median_depth;
  }
  return out;
}

int LocalMapSearch::Search(FrameId previous_frame, const std::optional<Pose>& T_prev_cur,
                           bool metric, const DetectedImage& cur,
                           std::vector<LandmarkId>* landmark,
                           std::vector<int>* track_length) const {
  if (!options_.enable || !map_ || map_->frame != previous_frame || map_->points.empty()) return 0;
  const Pose T_c_w = PredictPose(T_prev_cur, metric).inverse();
  std::unordered_set<LandmarkId> present;
  for (const LandmarkId& id : *landmark) {
    if (id.valid()) present.insert(id);
  }

  // The map points that may be in view, at their predicted pixels, with their last appearance.
  DetectedImage from;
  from.patch_size = cur.patch_size;
  from.patch_spacing = cur.patch_spacing;
  from.image_size = cur.image_size;
  std::vector<const Appearance*> source;
  std::vector<LandmarkId> source_id;
  std::vector<Eigen::Vector2d> predicted;
  for (const auto& [id, p_w] : map_->points) {
    if (present.count(id)) continue;
    const auto it = appearance_.find(id);
    if (it == appearance_.end()) continue;
    Eigen::Vector2d uv;
    if (!camera_.Project(T_c_w * p_w, &uv) || !camera_.InImage(uv)) continue;
    InterestPoint p = it->second.point;
    p.uv = uv;
    from.points.push_back(p);
    source.push_back(&it->second);
    source_id.push_back(id);
    predicted.push_back(uv);
  }
  if (from.points.empty()) return 0;
  const int n = cur.descriptors.cols;
  from.descriptors.create(static_cast<int>(source.size()), n, CV_32F);
  for (size_t k = 0; k < source.size(); ++k) {
    CHECK_EQ(static_cast<int>(source[k]->descriptor.size()), n);
    std::copy(source[k]->descriptor.begin(), source[k]->descriptor.end(),
              from.descriptors.ptr<float>(static_cast<int>(k)));
  }
  const MatchPrior prior = MatchPrior::Predicted(std::move(predicted), options_.radius_px);
  int assigned = 0;
  for (const Match& m : MatchPoints(from, cur, matcher_, &prior)) {
    if ((*landmark)[m.j].valid()) continue;  // Already tracked under another id.
    (*landmark)[m.j] = source_id[m.i];
    (*track_length)[m.j] = source[m.i]->track_length + 1;
    ++assigned;
  }
  return assigned;
}

void LocalMapSearch::Remember(FrameId frame, const DetectedImage& detection,
                              const std::vector<LandmarkId>& landmark,
                              const std::vector<int>& track_length) {
  if (!options_.enable) return;
  const int n = detection.descriptors.cols;
  for (size_t i = 0; i < landmark.size(); ++i) {
    if (!landmark[i].valid()) continue;
    Appearance& a = appearance_[landmark[i]];
    a.point = detection.points[i];
    const float* row = detection.descriptors.ptr<float>(static_cast<int>(i));
    a.descriptor.assign(row, row + n);
    a.track_length = track_length[i];
    a.last_seen = frame.value;
  }
  // Forget what is neither mapped nor recently seen (bounded memory).
  for (auto it = appearance_.begin(); it != appearance_.end();) {
    if (frame.value - it->second.last_seen > forget_after_frames_ && !IsMapped(it->first)) {
      it = appearance_.erase(it);
    } else {
      ++it;
    }
  }
}

void LocalMapSearch::RenameRemembered(FrameId frame,
                                      const std::unordered_map<LandmarkId, LandmarkId>& rename) {
  // Taken out first: an id may be both an old id and another pair's new one.
  std::vector<std::pair<LandmarkId, Appearance>> moved;
  for (const auto& [old, now] : rename) {
    const auto it = appearance_.find(old);
    if (it == appearance_.end() || it->second.last_seen != frame.value) continue;
    moved.emplace_back(now, it->second);
    if (!IsMapped(old)) appearance_.erase(it);
  }
  for (auto& [now, appearance] : moved) appearance_[now] = std::move(appearance);
}

}  // namespace dala
