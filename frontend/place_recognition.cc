#include "frontend/place_recognition.h"

#include <glog/logging.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <unordered_set>

#include "core/loop_turn.h"

namespace dala {

MotionEstimatorOptions PlaceRecognitionOptions::DefaultPnpOptions() {
  MotionEstimatorOptions o;
  // No prior pose: more samples than tracking, and a wider gate for the older points.
  o.ransac_max_iterations = 500;
  o.ransac_threshold_px = 3.0;
  o.min_inliers = 12;
  o.seed = 7;
  return o;
}

bool PlaceRecognitionOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (thumbnail_width < 4 || thumbnail_height < 4)
    return fail("loop.thumbnail_width and loop.thumbnail_height must be >= 4");
  if (thumbnail_width > static_cast<int>(kMaxThumbnailSide) ||
      thumbnail_height > static_cast<int>(kMaxThumbnailSide))
    return fail("loop.thumbnail_width and loop.thumbnail_height must be <= 1024 (a saved map's limit)");
  if (max_shift_x < 0 || max_shift_y < 0 || 2 * max_shift_x >= thumbnail_width ||
      2 * max_shift_y >= thumbnail_height)
    return fail("loop.max_shift_x/y must be >= 0 and less than half the thumbnail size");
  if (!(min_appearance_score >= -1.0 && min_appearance_score < 1.0))
    return fail("loop.min_appearance_score must be in [-1, 1)");
  if (top_k < 1) return fail("loop.top_k must be >= 1");
  if (min_frame_gap < 1) return fail("loop.min_frame_gap must be >= 1");
  if (!(gate_radius_m > 0.0) || !(gate_fraction >= 0.0))
    return fail("loop.gate_radius_m must be > 0 and loop.gate_fraction >= 0");
  if (!matcher.IsValid(why) || !pnp.IsValid(why)) return false;
  if (min_inliers < pnp.min_inliers) return fail("loop.min_inliers must be >= pnp.min_inliers");
  if (!(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0))
    return fail("loop.min_inlier_ratio must be in [0, 1]");
  if (keyframes_between_loops < 0) return fail("loop.keyframes_between_loops must be >= 0");
  if (!(gate_rotation_deg > 0.0) || !(gate_rotation_deg_per_m >= 0.0))
    return fail("loop.gate_rotation_deg must be > 0 and loop.gate_rotation_deg_per_m >= 0");
  if (!(mono_gate_fraction > 0.0)) return fail("loop.mono_gate_fraction must be > 0");
  if (relocalise_below_mapped < 0) return fail("loop.relocalise_below_mapped must be >= 0");
  if (!(place_min_inlier_fraction >= 0.0 && place_min_inlier_fraction <= 1.0))
    return fail("loop.place_min_inlier_fraction must be in [0, 1]");
  if (!(place_prior_radius_px > 0.0)) return fail("loop.place_prior_radius_px must be > 0");
  if (mono_max_entry_points < min_inliers)
    return fail("loop.mono_max_entry_points must be >= loop.min_inliers");
  return true;
}

PlaceRecognition::PlaceRecognition(const StereoRig& rig, const PlaceRecognitionOptions& options)
    : rig_(rig), options_(options), pnp_(rig, options.pnp) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
}

cv::Mat PlaceRecognition::GlobalDescriptor(const cv::Mat& gray,
                                           const PlaceRecognitionOptions& options) {
  CHECK_EQ(gray.type(), CV_8UC1) << "GlobalDescriptor expects an 8-bit grey image";
  cv::Mat small, out;
  cv::resize(gray, small, cv::Size(options.thumbnail_width, options.thumbnail_height), 0, 0,
             cv::INTER_AREA);
  small.convertTo(out, CV_32F);
  const cv::Scalar mean = cv::mean(out);
  out -= mean[0];
  const double norm = cv::norm(out);
  if (norm > 1e-6) out /= norm;
  return out;
}

double PlaceRecognition::AppearanceScore(const cv::Mat& a, const cv::Mat& b,
                                         const PlaceRecognitionOptions& options) {
  CHECK(a.size() == b.size() && a.type() == CV_32F && b.type() == CV_32F)
      << "AppearanceScore: descriptors of different sizes or types";
  // ZNCC over the overlap of a and b shifted by (dx, dy): means and norms of the overlap.
  double best = -1.0;
  for (int dy = -options.max_shift_y; dy <= options.max_shift_y; ++dy) {
    for (int dx = -options.max_shift_x; dx <= options.max_shift_x; ++dx) {
      const int x0 = std::max(0, -dx), x1 = std::min(a.cols, a.cols - dx);
      const int y0 = std::max(0, -dy), y1 = std::min(a.rows, a.rows - dy);
      double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
      for (int y = y0; y < y1; ++y) {
        const float* pa = a.ptr<float>(y);
        const float* pb = b.ptr<float>(y + dy);
        for (int x = x0; x < x1; ++x) {
          const double va = pa[x], vb = pb[x + dx];
          sa += va;
          sb += vb;
          saa += va * va;
          sbb += vb * vb;
          sab += va * vb;
        }
      }
      const double n = static_cast<double>(x1 - x0) * (y1 - y0);
      const double cov = sab - sa * sb / n;
      const double var = (saa - sa * sa / n) * (sbb - sb * sb / n);
      if (var <= 1e-18) continue;
      best = std::max(best, cov / std::sqrt(var));
    }
  }
  return best;
}

KeyframeEntry PlaceRecognition::MakeEntry(FrameId frame, int64_t t_ns, const Pose& T_w_c,
                                          double path_length_m, const cv::Mat& left,
                                          const DetectedImage& detection,
                                          const std::vector<std::optional<StereoPoint>>& stereo,
                                          const std::vector<LandmarkId>& landmark) const {
  CHECK_EQ(stereo.size(), detection.points.size());
  CHECK_EQ(landmark.size(), detection.points.size());
  KeyframeEntry e;
  e.frame = frame;
  e.t_ns = t_ns;
  e.T_w_c = T_w_c;
  e.path_length_m = path_length_m;
  e.global_descriptor = GlobalDescriptor(left, options_);
  e.image_size = detection.image_size;
  e.patch_size = detection.patch_size;
  e.patch_spacing = detection.patch_spacing;
  // Stereo: the points with a stereo depth. One camera: the points with a landmark id, those
  // with a 3D point (mapped) first, then the strongest corners, at most mono_max_entry_points.
  std::vector<int> rows;
  for (size_t i = 0; i < stereo.size(); ++i) {
    if ((stereo[i] || !rig_.is_stereo()) && landmark[i].valid()) rows.push_back(static_cast<int>(i));
  }
  if (!rig_.is_stereo() && static_cast<int>(rows.size()) > options_.mono_max_entry_points) {
    std::stable_sort(rows.begin(), rows.end(), [&](int a, int b) {
      if (stereo[a].has_value() != stereo[b].has_value()) return stereo[a].has_value();
      return detection.points[a].cornerness > detection.points[b].cornerness;
    });
    rows.resize(options_.mono_max_entry_points);
    std::sort(rows.begin(), rows.end());
  }
  e.descriptors = QuantizedDescriptors(detection.descriptors.cols);
  for (size_t k = 0; k < rows.size(); ++k) {
    const int i = rows[k];
    e.points.push_back(detection.points[i]);
    e.descriptors.AppendRow(detection.descriptors, i);
    e.landmark.push_back(landmark[i]);
    e.stereo.push_back(stereo[i]);
  }
  return e;
}

bool PlaceRecognition::WithinGate(const KeyframeEntry& old, const KeyframeEntry& query,
                                  const Eigen::Vector3d& t_w_cur) const {
  if (!options_.spatial_gate) return true;
  const double path = std::abs(query.path_length_m - old.path_length_m);
  // One camera: positions and paths in the map's arbitrary unit, whose scale drifts.
  const double radius = rig_.is_stereo() ? options_.gate_radius_m + options_.gate_fraction * path
                                         : options_.mono_gate_fraction * path;
  return (t_w_cur - query.T_w_c.translation()).norm() <= radius;
}

bool PlaceRecognition::WithinRotationGate(const KeyframeEntry& old, const KeyframeEntry& query,
                                          const Eigen::Matrix3d& R_w_cur) const {
  if (!options_.spatial_gate || !rig_.is_stereo()) return true;
  const double path = std::abs(query.path_length_m - old.path_length_m);
  // How far the loop would turn the dead-reckoned camera.
  return CheckLoopTurn(query.T_w_c.rotation(), R_w_cur, path, options_.gate_rotation_deg,
                       options_.gate_rotation_deg_per_m)
      .within;
}

bool PlaceRecognition::LeftAndCameBack(const KeyframeEntry& old,
                                       const KeyframeEntry& query) const {
  // Stereo: a camera that travelled less than twice the gate's radius since the old keyframe
  // cannot have left the radius around it and come back; the old view is the current map's, and
  // "closing" it can only bend the window (a slow rig at 30 fps passes min_frame_gap within
  // 4 m; docs/results.md, stop 48). One camera's path has no metric unit: min_frame_gap alone.
  if (!options_.spatial_gate || !rig_.is_stereo()) return true;
  return std::abs(query.path_length_m - old.path_length_m) >= 2.0 * options_.gate_radius_m;
}

std::optional<PlaceMatch> PlaceRecognition::Verify(
    const KeyframeEntry& old, const KeyframeEntry& query, const DetectedImage& detection,
    const std::vector<std::optional<StereoPoint>>& stereo, const std::vector<LandmarkId>& landmark,
    bool* rejected_by_gate, bool gate, const std::optional<Pose>& T_old_cur_guess) const {
  if (rejected_by_gate) *rejected_by_gate = false;
  if (static_cast<int>(old.size()) < options_.min_inliers) return std::nullopt;
  std::optional<MatchPrior> prior;
  if (T_old_cur_guess && rig_.is_stereo()) {
    const Pose T_cur_old = T_old_cur_guess->inverse();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<Eigen::Vector2d> predicted(old.size(), Eigen::Vector2d(nan, nan));
    for (size_t k = 0; k < old.size(); ++k) {
      Eigen::Vector2d uv;
      if (old.stereo[k] && rig_.left.Project(T_cur_old * old.stereo[k]->p_c0, &uv)) {
        predicted[k] = uv;
      }
    }
    prior = MatchPrior::Predicted(std::move(predicted), options_.place_prior_radius_px);
  }
  const std::vector<Match> matches =
      MatchPoints(old.Detection(), detection, options_.matcher, prior ? &*prior : nullptr);
  VLOG(2) << "place recognition: keyframe " << old.frame << " (" << old.size() << " points): "
          << matches.size() << " matches";
  if (static_cast<int>(matches.size()) < options_.min_inliers) return std::nullopt;
  if (!rig_.is_stereo()) return VerifyMono(old, detection, landmark, matches);
  std::vector<MotionCorrespondence> corrs;
  corrs.reserve(matches.size());
  for (const Match& m : matches) {
    MotionCorrespondence c;
    c.p_prev = old.stereo[m.i]->p_c0;
    c.cov_p_prev = old.stereo[m.i]->cov_p_c0;
    c.uv_cur = detection.points[m.j].uv;
    if (stereo[m.j]) c.u_right_cur = stereo[m.j]->u_right;
    corrs.push_back(c);
  }
  const std::optional<MotionResult> pnp = pnp_.Estimate3D2D(corrs);
  VLOG(2) << "place recognition: keyframe " << old.frame << ": PnP "
          << (pnp ? std::to_string(pnp->estimate.inliers) + " inliers" : "failed");
  if (!pnp) return std::nullopt;
  const int inliers = pnp->estimate.inliers;
  if (inliers < options_.min_inliers ||
      inliers < options_.min_inlier_ratio * static_cast<double>(matches.size())) {
    return std::nullopt;
  }
  const Pose T_w_cur_loop = old.T_w_c * pnp->estimate.T_prev_cur;
  if (gate && (!WithinGate(old, query, T_w_cur_loop.translation()) ||
               !WithinRotationGate(old, query, T_w_cur_loop.rotation()))) {
    if (rejected_by_gate) *rejected_by_gate = true;
    return std::nullopt;
  }
  return MakeMatch(old, landmark, matches, pnp->estimate, pnp->inlier);
}

std::optional<PlaceMatch> PlaceRecognition::VerifyMono(const KeyframeEntry& old,
                                                       const DetectedImage& detection,
                                                       const std::vector<LandmarkId>& landmark,
                                                       const std::vector<Match>& matches) const {
  std::vector<Eigen::Vector2d> uv_old, uv_cur;
  for (const Match& m : matches) {
    uv_old.push_back(old.points[m.i].uv);
    uv_cur.push_back(detection.points[m.j].uv);
  }
  // A revisit from nearly the same viewpoint leaves the epipolar geometry degenerate: the
  // rotation's homography then verifies the matches instead; the model with more inliers wins.
  std::optional<MotionResult> best = pnp_.EstimateEssential(uv_old, uv_cur);
  const std::optional<MotionResult> rotation = pnp_.EstimateRotation(uv_old, uv_cur);
  if (rotation && (!best || rotation->estimate.inliers > best->estimate.inliers)) best = rotation;
  if (!best) return std::nullopt;
  const int inliers = best->estimate.inliers;
  if (inliers < options_.min_inliers ||
      inliers < options_.min_inlier_ratio * static_cast<double>(matches.size())) {
    return std::nullopt;
  }
  return MakeMatch(old, landmark, matches, best->estimate, best->inlier);
}

PlaceMatch PlaceRecognition::MakeMatch(const KeyframeEntry& old,
                                       const std::vector<LandmarkId>& landmark,
                                       const std::vector<Match>& matches,
                                       const MotionEstimate& estimate,
                                       const std::vector<bool>& inlier) const {
  PlaceMatch out;
  out.loop.old_frame = old.frame;
  out.loop.T_old_cur = estimate.T_prev_cur;
  out.loop.cov = estimate.cov;
  out.loop.inliers = estimate.inliers;
  out.loop.correspondences = static_cast<int>(matches.size());
  // Relabel: an inlier's current point takes the old landmark id, unless that id is already
  // carried by another current point (a track that survived the gap) or it is the same id.
  std::unordered_set<LandmarkId> present(landmark.begin(), landmark.end());
  for (size_t c = 0; c < matches.size(); ++c) {
    if (!inlier[c]) continue;
    const LandmarkId old_id = old.landmark[matches[c].i];
    const LandmarkId cur_id = landmark[matches[c].j];
    if (old_id == cur_id || present.count(old_id)) continue;
    present.insert(old_id);
    out.loop.relabelled.emplace_back(cur_id, old_id);
    out.current_point.push_back(matches[c].j);
  }
  return out;
}

void PlaceRecognition::AddSavedKeyframe(const SavedKeyframe& keyframe, int patch_size,
                                        double patch_spacing,
                                        const std::unordered_map<LandmarkId, Eigen::Vector3d>& p_w) {
  KeyframeEntry e;
  e.frame = keyframe.frame;
  e.t_ns = keyframe.t_ns;
  e.T_w_c = keyframe.T_w_c;
  CHECK_EQ(keyframe.thumbnail.size(),
           static_cast<size_t>(options_.thumbnail_width) * options_.thumbnail_height)
      << "a saved keyframe's thumbnail must have this place recognition's size";
  e.global_descriptor = cv::Mat(options_.thumbnail_height, options_.thumbnail_width, CV_32F,
                                const_cast<float*>(keyframe.thumbnail.data()))
                            .clone();
  e.patch_size = patch_size;
  e.patch_spacing = patch_spacing;
  e.image_size = cv::Size(rig_.left.width, rig_.left.height);
  const Pose T_c_w = keyframe.T_w_c.inverse();
  std::vector<const SavedKeyframePoint*> rows;
  for (const SavedKeyframePoint& p : keyframe.points) {
    if (!p.landmark.valid()) continue;
    if (rig_.is_stereo() && !p_w.count(p.landmark)) continue;
    CHECK_EQ(p.descriptor.size(), static_cast<size_t>(patch_size * patch_size));
    rows.push_back(&p);
  }
  e.descriptors = QuantizedDescriptors(patch_size * patch_size);
  for (size_t k = 0; k < rows.size(); ++k) {
    const SavedKeyframePoint& p = *rows[k];
    InterestPoint ip;
    ip.uv = p.uv;
    ip.orientation = p.orientation;
    ip.scale = p.scale;
    ip.lambda1 = p.lambda1;
    ip.lambda2 = p.lambda2;
    e.points.push_back(ip);
    e.descriptors.AppendQuantized(p.descriptor.data());
    e.landmark.push_back(p.landmark);
    std::optional<StereoPoint> point;
    const auto it = p_w.find(p.landmark);
    if (it != p_w.end()) {
      // The map's optimised landmark in the keyframe's camera (no covariance: a map point).
      point = StereoPoint();
      point->p_c0 = T_c_w * it->second;
    }
    e.stereo.push_back(point);
  }
  saved_map_.Add(std::move(e));
}

std::vector<std::pair<double, const KeyframeEntry*>> PlaceRecognition::RankCandidates(
    const KeyframeEntry& query, bool relocalisation) {
  std::vector<std::pair<double, const KeyframeEntry*>> scored;
  const auto score_entry = [&](const KeyframeEntry& e) {
    const double score = AppearanceScore(e.global_descriptor, query.global_descriptor, options_);
    if (score > stats_.best_score) {
      stats_.best_score = score;
      stats_.best_frame = e.frame;
    }
    if (score >= options_.min_appearance_score) scored.emplace_back(score, &e);
  };
  if (relocalisation) {
    for (const KeyframeEntry& e : saved_map_.entries()) {
      ++stats_.searched;
      score_entry(e);
    }
  }
  for (const KeyframeEntry& e : database_.entries()) {
    if (!relocalisation && query.frame.value - e.frame.value < options_.min_frame_gap) {
      break;  // Time order: the rest are younger still.
    }
    ++stats_.searched;
    if (!relocalisation && !LeftAndCameBack(e, query)) {
      ++stats_.gated_out;
      continue;
    }
    if (!relocalisation && !WithinGate(e, query, e.T_w_c.translation())) {
      ++stats_.gated_out;
      continue;
    }
    score_entry(e);
  }
  // Best first; ties keep the scan order (the saved map, then older first): deterministic.
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  if (static_cast<int>(scored.size()) > options_.top_k) scored.resize(options_.top_k);
  return scored;
}

std::optional<PlaceMatch> PlaceRecognition::VerifyCandidates(
    const std::vector<std::pair<double, const KeyframeEntry*>>& ranked,
    const KeyframeEntry& query, const DetectedImage& detection,
    const std::vector<std::optional<StereoPoint>>& stereo,
    const std::vector<LandmarkId>& landmark, bool gate) {
  for (const auto& [score, entry] : ranked) {
    ++stats_.candidates;
    bool rejected = false;
    std::optional<PlaceMatch> found =
        Verify(*entry, query, detection, stereo, landmark, &rejected, gate);
    stats_.rejected_by_gate |= rejected;
    if (found) {
      found->loop.appearance_score = score;
      stats_.best_inliers = std::max(stats_.best_inliers, found->loop.inliers);
      return found;
    }
  }
  return std::nullopt;
}

std::optional<PlaceMatch> PlaceRecognition::Search(
    const KeyframeEntry& query, const DetectedImage& detection,
    const std::vector<std::optional<StereoPoint>>& stereo,
    const std::vector<LandmarkId>& landmark, bool relocalisation) {
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<PlaceMatch> found =
      VerifyCandidates(RankCandidates(query, relocalisation), query, detection, stereo, landmark,
                       /*gate=*/!relocalisation);
  stats_.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return found;
}

std::optional<PlaceMatch> PlaceRecognition::Detect(
    const KeyframeEntry& query, const DetectedImage& detection,
    const std::vector<std::optional<StereoPoint>>& stereo,
    const std::vector<LandmarkId>& landmark) {
  stats_ = PlaceRecognitionStats();
  ++keyframes_since_loop_;
  if (!options_.enable || keyframes_since_loop_ <= options_.keyframes_between_loops) {
    return std::nullopt;
  }
  std::optional<PlaceMatch> found =
      Search(query, detection, stereo, landmark, /*relocalisation=*/false);
  if (found) keyframes_since_loop_ = 0;
  return found;
}

std::optional<FrameId> PlaceRecognition::HeldBy(
    const KeyframeEntry& query, const std::optional<PlaceMatch>& loop,
    const DetectedImage& detection, const std::vector<std::optional<StereoPoint>>& stereo,
    const std::vector<LandmarkId>& landmark) {
  const std::optional<FrameId> previous = last_holder_;
  last_holder_.reset();
  if (!options_.one_entry_per_place) return std::nullopt;
  const double min_inliers = std::max<double>(
      options_.min_inliers, options_.place_min_inlier_fraction * static_cast<double>(query.size()));
  const Pose T_w_prev = last_query_T_w_c_;
  last_query_T_w_c_ = query.T_w_c;
  if (loop && loop->loop.inliers >= min_inliers) {
    last_holder_ = loop->loop.old_frame;
    last_holder_T_old_prev_ = loop->loop.T_old_cur;
    return last_holder_;
  }
  if (!previous) return std::nullopt;
  const std::optional<size_t> at = database_.IndexOf(*previous);
  if (!at) return std::nullopt;
  const KeyframeEntry& holder = database_.entries()[*at];
  // The old path's next keyframe first, then the same one, then two and three ahead.
  for (const int step : {1, 0, 2, 3}) {
    const size_t i = *at + step;
    if (i >= database_.size()) break;
    const KeyframeEntry& old = database_.entries()[i];
    if (query.frame.value - old.frame.value < options_.min_frame_gap) break;
    // T_old_cur = T_old_holder (old lap's dead reckoning) * T_holder_prev (verified)
    //             * T_prev_cur (this lap's dead reckoning): each a short, local motion.
    const Pose guess = old.T_w_c.inverse() * holder.T_w_c * last_holder_T_old_prev_ *
                       T_w_prev.inverse() * query.T_w_c;
    const std::optional<PlaceMatch> held =
        Verify(old, query, detection, stereo, landmark, nullptr, true, guess);
    if (held && held->loop.inliers >= min_inliers) {
      last_holder_ = old.frame;
      last_holder_T_old_prev_ = held->loop.T_old_cur;
      return last_holder_;
    }
  }
  return std::nullopt;
}

std::optional<PlaceMatch> PlaceRecognition::Relocalize(
    const KeyframeEntry& query, const DetectedImage& detection,
    const std::vector<std::optional<StereoPoint>>& stereo,
    const std::vector<LandmarkId>& landmark) {
  stats_ = PlaceRecognitionStats();
  if (!options_.relocalise) return std::nullopt;
  return Search(query, detection, stereo, landmark, /*relocalisation=*/true);
}

}  // namespace dala
