#include "backend/system.h"

#include <glog/logging.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_set>

#include "backend/ekf/mono_ekf.h"
#include "backend/ekf/stereo_ekf.h"
#include "backend/sliding_window_estimator.h"
#include "core/error.h"
#include "core/quantized_descriptors.h"

namespace dala {

std::unique_ptr<Estimator> MakeEstimator(const StereoRig& rig, const SystemOptions& options) {
  if (options.estimator == "ba") {
    // Stereo or mono by the rig (System gives a mono rig in mode "mono").
    if ((options.mode == "stereo") != rig.is_stereo()) {
      throw Error() << "estimator 'ba' in mode '" << options.mode << "' needs a "
                    << (rig.is_stereo() ? "monocular" : "stereo") << " rig";
    }
    return std::make_unique<SlidingWindowEstimator>(rig, options.ba);
  }
  if (options.estimator == "ekf" && options.mode == "stereo") {
    return std::make_unique<StereoEkfEstimator>(rig, options.ekf_stereo);
  }
  if (options.estimator == "ekf" && options.mode == "mono") {
    // With mono_stereo_motion the frontend runs stereo: its visual motion is the mono EKF's
    // scale-fixing dead reckoning (as on the paper's robots); the filter uses left pixels only.
    MonoEkfOptions ekf_mono = options.ekf_mono;
    ekf_mono.mono_init = options.ba.mono_init;  // Section "mono_init": both mono estimators.
    return std::make_unique<MonoEkfEstimator>(rig.left, ekf_mono);
  }
  throw Error() << "estimator '" << options.estimator << "' in mode '" << options.mode
                << "' is not supported; available: ba/stereo, ba/mono, ekf/stereo, ekf/mono";
}

System::System(const StereoRig& rig, const SystemOptions& options) : rig_(rig), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw Error() << "invalid options: " << why;
  if (!rig_.left.IsValid(&why)) throw Error() << "invalid calibration: " << why;
  if (options_.mode == "stereo" && !rig_.is_stereo()) {
    throw Error() << "stereo mode needs a stereo dataset; this one is monocular: use --mode mono";
  }
  if (options_.mono_stereo_motion && !rig_.is_stereo()) {
    throw Error() << "mono_stereo_motion needs a stereo dataset (its visual motion feeds the mono "
                     "EKF); this one is monocular: drop --set mono_stereo_motion=1";
  }
  // Mode "mono" is one camera: the right image, if any, is never used.
  if (options_.mode == "mono" && !options_.mono_stereo_motion) rig_.baseline = 0.0;
  if (options_.estimator == "ba" && !options_.ba.IsValidFor(rig_, &why)) {
    throw Error() << "invalid options: " << why;
  }
  // One order seed for every OpenCV RANSAC of the run (SystemOptions::ransac_order_seed).
  const uint64_t order_seed = options_.ransac_order_seed;
  options_.frontend.tracking_matcher.ransac_order_seed = order_seed;
  options_.frontend.loop.matcher.ransac_order_seed = order_seed;
  options_.frontend.motion.ransac_order_seed = order_seed;
  options_.ba.mono_init.two_view.ransac_order_seed = order_seed;
  options_.ba.ransac_order_seed = order_seed;
  // One orientation gate for loops: the stereo rig's in the place recognition, one camera's in
  // the estimator's Sim(3) loop closure (BaLoopClosureOptions::mono_max_turn_deg).
  options_.ba.loop.mono_turn_gate = options_.frontend.loop.spatial_gate;
  options_.ba.loop.mono_max_turn_deg = options_.frontend.loop.gate_rotation_deg;
  options_.ba.loop.mono_max_turn_deg_per_unit = options_.frontend.loop.gate_rotation_deg_per_m;
  estimator_ = MakeEstimator(rig_, options_);
  frontend_ = std::make_unique<Frontend>(rig_, options_.frontend);
}

TrackResult System::Track(const Frame& frame) { return TrackFrame(frame, nullptr); }

TrackResult System::Track(const Frame& frame, const FrameFeatures& features) {
  return TrackFrame(frame, &features);
}

TrackResult System::TrackFrame(const Frame& frame, const FrameFeatures* features) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (!stats_.empty() && frame.t_ns < stats_.back().t_ns) {
    throw Error() << "frame " << frame.id.value << " at t_ns " << frame.t_ns
                  << " comes before the previous frame (t_ns " << stats_.back().t_ns
                  << "): give System::Track the frames in time order";
  }
  FrameMeasurement m =
      features != nullptr ? frontend_->Process(frame, *features) : frontend_->Process(frame);
  if (options_.use_odometry && frame.T_w_odom && T_w_odom_prev_) {
    // Odometry between the previous frame and this one (SystemOptions::use_odometry).
    MotionEstimate odometry;
    odometry.T_prev_cur = T_w_odom_prev_->inverse() * *frame.T_w_odom;
    const double sr = options_.odometry_sigma_rot;
    const double st = options_.odometry_sigma_trans +
                      options_.odometry_sigma_trans_fraction * odometry.T_prev_cur.translation().norm();
    Vector6d var;
    var << sr * sr, sr * sr, sr * sr, st * st, st * st, st * st;
    odometry.cov = var.asDiagonal();
    m.odometry = odometry;
    odometry_given_ = true;
  }
  T_w_odom_prev_ = frame.T_w_odom;
  const auto t1 = Clock::now();
  // Here, where Add would wait for a background window solve anyway (map() waits for it too).
  if (keyframe_records_.size() >= pruned_records_ + kRecordPruneAge + kRecordPruneEvery) {
    PruneKeyframeRecords(estimator_->map());
  }
  EstimatorOutput e = estimator_->Add(m);
  const LocalMapSearchOptions& search = options_.frontend.local_map;
  // Stereo runs get it too, for the relocalisation after a lost frame; their guided search and
  // keyframe evidence use it only while local_map.stereo_when_tracked_below holds (frontend.h). A lost frame is handed
  // over even with an empty map (a window of lost keyframes holds no landmark), so that the
  // frontend knows to relocalise; estimators that never hand a map (the EKFs) are left alone.
  if (search.enable && (!e.local_map.empty() || (!e.valid && local_map_handed_))) {
    local_map_handed_ = true;
    frontend_->SetLocalMap({frame.id, e.T_w_c, e.valid, std::move(e.local_map)});
  }
  frontend_->SetEstimatorInitializing(e.initializing);
  if (m.loop && e.loop_refused) {
    frontend_->ReturnLoopIds(*m.loop);
    // The refused loop's old keyframe does not hold this keyframe's place (saved below).
    if (PlaceReleasedByRefusedLoop(m, e.loop_refused)) m.place_held_by.reset();
  }
  const auto t2 = Clock::now();

  FrameStats s;
  s.frame = frame.id;
  s.t_ns = frame.t_ns;
  // A frame the estimator could not place is lost, whatever the frontend's motion said.
  s.status = e.initializing ? TrackingStatus::kInitializing
                            : (e.valid ? m.status : TrackingStatus::kLost);
  s.valid = e.valid;
  s.note = e.note;
  s.keyframe = m.is_keyframe;
  s.places = static_cast<int>(places());
  s.keyframes_in_map = e.keyframes_in_map;
  s.disparity_offset_px = e.disparity_offset_px;
  s.features = static_cast<int>(m.observations.size());
  for (const FeatureObservation& o : m.observations) s.tracked += o.track_length > 1;
  s.landmarks = e.landmarks_in_state;
  s.loop = m.loop.has_value();
  s.loop_closed = e.loop_closed;
  if (m.loop) s.loop_old_frame = m.loop->old_frame;
  s.loop_not_closed = e.loop_not_closed;
  s.frontend = m.timings;
  s.estimator_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
  s.total_ms = std::chrono::duration<double, std::milli>(t2 - t0).count();
  stats_.push_back(s);
  // A mono keyframe the estimator could not place is no keyframe of the map (it has a guessed
  // pose); a stereo one always joins the window.
  // A keyframe whose place an older keyframe holds (one entry per place) is not saved twice.
  if (m.is_keyframe && (e.valid || rig_.is_stereo()) && !m.place_held_by) {
    RecordKeyframe(frame.left);
  }

  TrackResult r;
  r.status = s.status;
  r.T_w_c = e.T_w_c;
  r.valid = e.valid;
  r.keyframe = m.is_keyframe;
  last_measurement_ = std::move(m);
  return r;
}

void System::SkipFrame(FrameId frame, int64_t t_ns, const std::string& note) {
  FrameStats s;
  s.frame = frame;
  s.t_ns = t_ns;
  s.status = TrackingStatus::kLost;
  s.valid = false;
  s.skipped = true;
  s.note = note;
  stats_.push_back(s);
}

void System::RecordKeyframe(const cv::Mat& left) {
  SavedKeyframe record;
  // The place recognition's thumbnail: what ranks this keyframe when a run relocalises in the
  // saved map.
  const cv::Mat thumbnail = PlaceRecognition::GlobalDescriptor(left, options_.frontend.loop);
  CHECK(thumbnail.isContinuous());
  record.thumbnail.assign(thumbnail.ptr<float>(), thumbnail.ptr<float>() + thumbnail.total());
  const DetectedImage* detection = frontend_->keyframe_detection();
  const std::vector<LandmarkId>* landmarks = frontend_->keyframe_landmarks();
  if (detection != nullptr && landmarks != nullptr) {
    const int n = detection->patch_size * detection->patch_size;
    for (size_t i = 0; i < landmarks->size(); ++i) {
      if (!(*landmarks)[i].valid()) continue;
      const InterestPoint& p = detection->points[i];
      SavedKeyframePoint saved;
      saved.landmark = (*landmarks)[i];
      saved.uv = p.uv;
      saved.orientation = p.orientation;
      saved.scale = p.scale;
      saved.lambda1 = p.lambda1;
      saved.lambda2 = p.lambda2;
      saved.descriptor.resize(n);
      QuantizeDescriptor(detection->descriptors.ptr<float>(static_cast<int>(i)), n,
                         saved.descriptor.data());
      record.points.push_back(std::move(saved));
    }
  }
  keyframe_records_.push_back(std::move(record));
  keyframe_trajectory_index_.push_back(stats_.size() - 1);
  keyframe_has_pose_.push_back(false);
}

void System::PruneKeyframeRecords(const std::vector<MapPoint>& map) const {
  if (keyframe_records_.size() <= pruned_records_ + kRecordPruneAge) return;
  std::unordered_set<int64_t> mapped;
  for (const MapPoint& p : map) mapped.insert(p.id.value);
  const size_t end = keyframe_records_.size() - kRecordPruneAge;
  for (size_t k = pruned_records_; k < end; ++k) {
    std::vector<SavedKeyframePoint>& points = keyframe_records_[k].points;
    points.erase(std::remove_if(points.begin(), points.end(),
                                [&mapped](const SavedKeyframePoint& p) {
                                  return mapped.count(p.landmark.value) == 0;
                                }),
                 points.end());
    points.shrink_to_fit();
  }
  pruned_records_ = end;
}

void System::RefreshKeyframePoses() const {
  // The trajectory leaves out the frames without a pose (mono before its initialisation):
  // match by time.
  const Trajectory trajectory = estimator_->trajectory();
  std::map<int64_t, const Pose*> pose_at;
  for (const StampedPose& p : trajectory.poses) pose_at[p.t_ns] = &p.T_w_c;
  for (size_t k = 0; k < keyframe_records_.size(); ++k) {
    const FrameStats& s = stats_[keyframe_trajectory_index_[k]];
    keyframe_records_[k].frame = s.frame;
    keyframe_records_[k].t_ns = s.t_ns;
    const auto it = pose_at.find(s.t_ns);
    keyframe_has_pose_[k] = it != pose_at.end();
    if (keyframe_has_pose_[k]) keyframe_records_[k].T_w_c = *it->second;
  }
}

std::vector<SavedKeyframe> System::keyframes() const {
  PruneKeyframeRecords(estimator_->map());
  RefreshKeyframePoses();
  std::vector<SavedKeyframe> out;
  for (size_t k = 0; k < keyframe_records_.size(); ++k) {
    if (keyframe_has_pose_[k]) out.push_back(keyframe_records_[k]);
  }
  return out;
}

RefinementSummary System::Finish(const std::function<bool()>& stop_requested) {
  return estimator_->Refine(stop_requested);
}

std::string System::ScaleDescription() const {
  if (options_.mode == "stereo") return "metric (stereo)";
  if (saved_map_metric_) {
    return *saved_map_metric_ ? "metric (the saved map's)" : "arbitrary (the saved map's unit)";
  }
  // The mono EKF prefers the odometry to the stereo motion (backend/ekf/mono_ekf.h).
  if (options_.estimator == "ekf" && odometry_given_) return "metric (odometry)";
  if (options_.mono_stereo_motion) return "metric (stereo visual motion)";
  return "arbitrary (monocular)";
}

namespace {

// The map without its keyframes: landmarks, the descriptor and thumbnail sizes, the unit.
SavedMap MapWithoutKeyframes(const std::vector<SavedKeyframe>& keyframes,
                             const std::vector<MapPoint>& points, const SystemOptions& options,
                             bool metric) {
  SavedMap map;
  map.metric = metric;
  map.thumbnail_width = options.frontend.loop.thumbnail_width;
  map.thumbnail_height = options.frontend.loop.thumbnail_height;
  for (const SavedKeyframe& kf : keyframes) {
    if (!kf.points.empty()) map.descriptor_size = static_cast<int>(kf.points[0].descriptor.size());
  }
  for (const MapPoint& p : points) map.landmarks.push_back({p.id, p.p_w, p.observations});
  return map;
}

}  // namespace

void System::SaveMap(const std::string& path) const {
  const std::vector<MapPoint> points = estimator_->map();
  PruneKeyframeRecords(points);
  RefreshKeyframePoses();
  SavedMap map = MapWithoutKeyframes(keyframe_records_, points, options_, IsMetric());
  if (std::count(keyframe_has_pose_.begin(), keyframe_has_pose_.end(), false) > 0) {
    // Some keyframes have no pose (mono before its initialisation): write a copy without them.
    WriteMapFile(path, map, keyframes());
  } else {
    WriteMapFile(path, map, keyframe_records_);
  }
}

bool IsMetricScale(const std::string& scale_description) {
  return scale_description.rfind("metric", 0) == 0;
}

bool System::IsMetric() const { return IsMetricScale(ScaleDescription()); }

SavedMap System::LoadMap(const std::string& path) { return ReadMapFile(path); }

void System::UseMap(const SavedMap& map) {
  if (!stats_.empty()) throw Error() << "a saved map must be given before the first frame";
  if (saved_map_metric_) throw Error() << "a run starts in one saved map only";
  if (map.keyframes.empty() || map.landmarks.empty()) {
    throw Error() << "the saved map has no keyframes or no landmarks: nothing to relocalise in";
  }
  if (rig_.is_stereo() && !map.metric) {
    throw Error() << "the saved map was made from one camera (its unit is arbitrary): a stereo "
                     "run cannot continue it; run with --mode mono";
  }
  const FrontendOptions& f = options_.frontend;
  if (!f.loop.enable || !f.loop.relocalise) {
    throw Error() << "running in a saved map needs the place recognition and the relocalisation "
                     "(loop.enable=1, loop.relocalise=1)";
  }
  if (map.descriptor_size != f.harris.patch_size * f.harris.patch_size) {
    throw Error() << "the saved map's descriptors have " << map.descriptor_size
                  << " values, these options' " << f.harris.patch_size * f.harris.patch_size
                  << " (harris.patch_size " << f.harris.patch_size
                  << "): run with the options that made the map";
  }
  if (map.thumbnail_width != f.loop.thumbnail_width ||
      map.thumbnail_height != f.loop.thumbnail_height) {
    throw Error() << "the saved map's thumbnails are " << map.thumbnail_width << "x"
                  << map.thumbnail_height << ", these options' " << f.loop.thumbnail_width << "x"
                  << f.loop.thumbnail_height
                  << " (loop.thumbnail_width/height): run with the options that made the map";
  }
  if (!f.local_map.enable) {
    throw Error() << "running in a saved map needs the local-map search "
                     "(frontend.local_map_search=1): it tells the frontend when a frame is placed";
  }
  // A map from someone else: every value the place recognition and the matcher will use is
  // checked here (their CHECKs and index arithmetic assume sane values), ids below 2^62 so that
  // the run's new ids, which start after them, cannot overflow.
  constexpr int64_t kMaxId = int64_t{1} << 62;
  const size_t thumbnail_size = static_cast<size_t>(map.thumbnail_width) * map.thumbnail_height;
  const double max_u = 2.0 * rig_.left.width, max_v = 2.0 * rig_.left.height;
  for (size_t k = 0; k < map.keyframes.size(); ++k) {
    const SavedKeyframe& kf = map.keyframes[k];
    if (k > 0 && !(map.keyframes[k - 1].frame < kf.frame)) {
      throw Error() << "the saved map's keyframes are not in frame order (frame " << kf.frame
                    << " after " << map.keyframes[k - 1].frame << ")";
    }
    if (kf.thumbnail.size() != thumbnail_size || !kf.T_w_c.matrix().allFinite()) {
      throw Error() << "the saved map's keyframe " << kf.frame
                    << " has a thumbnail of another size or a non-finite pose";
    }
    for (const SavedKeyframePoint& p : kf.points) {
      const bool sane =
          p.landmark.value < kMaxId && p.uv.allFinite() && std::abs(p.uv.x()) < max_u &&
          std::abs(p.uv.y()) < max_v && std::isfinite(p.orientation) &&
          std::isfinite(p.scale) && p.scale > 0.f && p.scale < 1e3f && std::isfinite(p.lambda1) &&
          std::isfinite(p.lambda2) && p.lambda1 >= 0.f && p.lambda2 >= 0.f &&
          p.descriptor.size() == static_cast<size_t>(map.descriptor_size);
      if (!sane) {
        throw Error() << "the saved map's keyframe " << kf.frame << " has a point (landmark "
                      << p.landmark.value << ") with a position, orientation, scale, "
                      << "eigenvalue, descriptor size or id out of range";
      }
    }
  }
  std::vector<MapPoint> landmarks;
  for (const SavedLandmark& l : map.landmarks) {
    if (!l.id.valid() || l.id.value >= kMaxId || !l.p_w.allFinite()) {
      throw Error() << "the saved map has a landmark with id " << l.id.value
                    << " at a non-finite position or with an invalid id";
    }
    landmarks.push_back({l.id, l.p_w, l.observations});
  }
  if (!estimator_->UseMap(landmarks)) {
    throw Error() << "the estimator " << options_.estimator << "/" << options_.mode
                  << " cannot start in a saved map; use --estimator ba";
  }
  frontend_->UseMap(map);
  saved_map_metric_ = map.metric;
}

}  // namespace dala
