#include "backend/sliding_window_estimator.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <sstream>

#include "backend/mono/keyframe_bridge.h"
#include "core/cv_pose.h"

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
  if (!(mono_scale_sigma > 0 && mono_loop_scale_sigma > 0)) {
    if (why) *why = "ba.loop_mono_scale_sigma and ba.loop_mono_loop_scale_sigma must be > 0";
    return false;
  }
  if (!(mono_max_turn_deg > 0 && mono_max_turn_deg_per_unit >= 0)) {
    if (why) {
      *why = "the mono loop's turn gate (loop.gate_rotation_deg) must be > 0 and its per-unit "
             "term (loop.gate_rotation_deg_per_m) >= 0";
    }
    return false;
  }
  return sim3.IsValid(why);
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
  if (!(observation_sigma_px > 0) && observation_sigma_px != -1.0) {
    return fail("ba.sigma_px must be > 0, or -1 (by mode)");
  }
  if (!(tracking_sigma_px > 0)) return fail("ba.tracking_sigma_px must be > 0");
  if (mono_reinit_after_lost_frames < 1)
    return fail("ba.mono_reinit_after_lost_frames must be >= 1");
  if (refine_frames != "mono" && refine_frames != "always" && refine_frames != "off") {
    return fail("ba.refine_frames must be mono, always or off");
  }
  if (final_ba != "rig_offset" && final_ba != "after_loop" && final_ba != "always" &&
      final_ba != "off") {
    return fail("ba.final_ba must be rig_offset, after_loop, always or off");
  }
  if (global_ba.max_num_iterations < 1) return fail("ba.final_ba_max_iterations must be >= 1");
  if (!global_ba.IsValid(why)) return false;
  return mono_init.IsValid(why);
}

bool SlidingWindowEstimatorOptions::IsValidFor(const StereoRig& rig, std::string* why) const {
  if (!IsValid(why)) return false;
  // One camera: the gauge is 7 dof (pose + scale); two held keyframes carry it (0 or 1 leave
  // the scale free: measured 6-11 m ATE on KITTI 06 with 1).
  if (!rig.is_stereo() && ba.num_fixed_keyframes >= 0 && ba.num_fixed_keyframes < 2) {
    if (why) *why = "ba.num_fixed_keyframes must be >= 2 (or -1, automatic) with one camera";
    return false;
  }
  return true;
}

namespace {

StereoIntrinsics IntrinsicsOf(const StereoRig& rig, double disparity_offset_px = 0.0) {
  StereoIntrinsics K;
  K.fx = rig.left.fx;
  K.fy = rig.left.fy;
  K.cx = rig.left.cx;
  K.cy = rig.left.cy;
  K.baseline = rig.baseline;
  K.disparity_offset_px = disparity_offset_px;
  return K;
}

// See the class comment, "Frames between keyframes": ~20 KB each (a frame's observations).
constexpr size_t kMaxWaitingFrames = 200;

BaObservation ToBa(const FeatureObservation& o, double sigma_px) {
  BaObservation b;
  b.landmark = o.landmark;
  b.uv = o.uv;
  b.u_right = o.u_right;
  b.sigma_px = sigma_px;
  return b;
}

}  // namespace

double SlidingWindowEstimatorOptions::WindowSigmaPx(const StereoRig& rig) const {
  if (observation_sigma_px > 0) return observation_sigma_px;
  return rig.is_stereo() ? 0.5 : 0.35;
}

BaObservation SlidingWindowEstimator::AsKeyframeObservation(const FeatureObservation& o) const {
  return ToBa(o, options_.WindowSigmaPx(rig_));
}

BaObservation SlidingWindowEstimator::AsFrameObservation(const FeatureObservation& o) const {
  return ToBa(o, options_.tracking_sigma_px);
}

SlidingWindowEstimator::SlidingWindowEstimator(const StereoRig& rig,
                                               const SlidingWindowEstimatorOptions& options)
    : rig_(rig),
      options_(options),
      ba_(IntrinsicsOf(
              rig, options.ba.calibrate_disparity_offset ? 0.0 : options.ba.disparity_offset_px),
          options.ba) {
  std::string why;
  CHECK(options_.IsValidFor(rig_, &why)) << why;
  CHECK(!rig_.left.HasDistortion()) << "SlidingWindowEstimator expects rectified images";
  if (!rig_.is_stereo()) initializer_.emplace(rig_.left, options_.mono_init);
}

std::vector<BaObservation> SlidingWindowEstimator::WindowObservations(
    const FrameMeasurement& m) const {
  std::vector<BaObservation> out;
  for (const FeatureObservation& o : m.observations) {
    if (!unconfirmed_loop_landmarks_.count(o.landmark) && ba_.LandmarkPosition(o.landmark)) {
      out.push_back(AsFrameObservation(o));
    }
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
    const int cy = std::clamp(static_cast<int>(uv.y() * options_.grid_rows / rig_.left.height), 0,
                              options_.grid_rows - 1);
    return cy * options_.grid_cols + cx;
  };
  const bool stereo = rig_.is_stereo();
  for (const FeatureObservation& o : m.observations) {
    if (unconfirmed_loop_landmarks_.count(o.landmark)) continue;
    if (landmark_observations_.count(o.landmark)) {
      out.push_back(AsKeyframeObservation(o));
      ++cell_count[cell_of(o.uv)];
    } else if (stereo ? o.has_stereo() : last_keyframe_observations_.count(o.landmark) > 0) {
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
    out.push_back(AsKeyframeObservation(*o));
    if (stereo) {
      // The frontend triangulated d = u - u_right; the rig's model has d + offset, so the
      // depth is d / (d + offset) of the frontend's (x and y scale with it).
      const double d = o->disparity();
      const double corrected = d + ba_.disparity_offset_px();
      ba_.SetLandmarkPosition(o->landmark,
                              T_w_c * ((corrected > 0 ? d / corrected : 1.0) * o->p_c0));
    } else {
      // Mono: the previous keyframe's view of it makes the pair the window triangulates, and
      // the earlier window keyframes that saw the same track add theirs (a longer baseline and
      // more links between the window's keyframes; see the class comment).
      std::vector<std::pair<KeyframeId, const BaObservation*>> views;
      for (const auto& [id, seen] : earlier_keyframe_observations_) {
        const auto it = seen.find(o->landmark);
        if (it != seen.end() && ba_.KeyframePose(id)) views.emplace_back(id, &it->second);
      }
      views.emplace_back(last_keyframe_, &last_keyframe_observations_.at(o->landmark));
      for (const auto& [id, view] : views) {
        ba_.AddObservation(id, *view);
        ++landmark_observations_[o->landmark];
      }
    }
    anchor_.emplace(o->landmark, KeyframeId(num_keyframes_ - 1));
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

void SlidingWindowEstimator::SolveWindow(KeyframeId id) {
  RenameFused(ba_.FuseLandmarks());
  const SlidingWindowBa::Summary summary = ba_.Optimize();
  VLOG(2) << "keyframe " << id << ": " << summary.BriefReport();
  if (!summary.usable) LOG(WARNING) << "keyframe " << id << ": window solve not usable";
  VLOG(2) << "keyframe " << id << ": disparity offset " << ba_.disparity_offset_px() << " px";
  for (const auto& [landmark, p_w] : ba_.Landmarks()) map_points_[landmark] = p_w;
  // Every keyframe's latest estimate (window ones move, the others keep their exit value).
  for (const KeyframeId k : ba_.WindowKeyframes()) keyframe_poses_[k] = *ba_.KeyframePose(k);
}

std::optional<Pose> SlidingWindowEstimator::RecoverPose(const FrameMeasurement& m) const {
  return PnpPose(
      m, [&](LandmarkId id) { return unconfirmed_loop_landmarks_.count(id) == 0; },
      2 * options_.pose_only.min_inliers);
}

std::optional<Pose> SlidingWindowEstimator::PnpPose(const FrameMeasurement& m,
                                                    const std::function<bool(LandmarkId)>& use,
                                                    int min_inliers) const {
  std::vector<Eigen::Vector3d> object;
  std::vector<Eigen::Vector2d> image;
  std::vector<BaObservation> observations;
  for (const FeatureObservation& o : m.observations) {
    if (!use(o.landmark)) continue;
    const std::optional<Eigen::Vector3d> p_w = ba_.LandmarkPosition(o.landmark);
    if (!p_w) continue;
    object.push_back(*p_w);
    image.push_back(o.uv);
    observations.push_back(AsFrameObservation(o));
  }
  if (static_cast<int>(object.size()) < min_inliers) return std::nullopt;
  // Threshold: the chi-square 95 % bound of a 1-pixel observation (2 dof), as the BA's test.
  const PnpRansacResult pnp = SeededPnpRansac(object, image, rig_.left.K(),
                                              std::sqrt(kChi2Quantile95Dof2),
                                              options_.ransac_order_seed);
  if (!pnp.found || pnp.inliers < min_inliers) {
    VLOG(1) << "frame " << m.frame << ": PnP failed (" << pnp.inliers << " inliers of "
            << object.size() << ")";
    return std::nullopt;
  }
  const Pose guess = pnp.T_c_o.inverse();  // T_w_c from OpenCV's T_c_w.
  // Refined over the same landmarks, outliers rejected.
  const PoseOnlyResult r = EstimatePoseOnly(
      IntrinsicsOf(rig_, ba_.disparity_offset_px()), observations,
      [&](LandmarkId id) { return ba_.LandmarkPosition(id); }, guess, options_.pose_only);
  VLOG(1) << "frame " << m.frame << ": PnP " << pnp.inliers << " inliers of " << object.size()
          << ", pose-only " << PoseOnlyStatusName(r.status) << " (" << r.num_inliers << " inliers)";
  if (r.status != PoseOnlyStatus::kOk || r.num_inliers < min_inliers) return std::nullopt;
  return r.T_w_c;
}

TwoViewOptions SlidingWindowEstimator::BridgeTwoViewOptions() const {
  // The initialisation's tests (spread over the image, parallax, no ambiguous homography) but
  // not its point count: a bridge starts no map, it places one frame by the rotation and the
  // direction of 20 or more good points (fast 300 seed 2: a jerk leaves 45 tracks; refused at
  // 50, the frames after it are lost until a new map starts, 15 of them).
  constexpr int kBridgeMinPoints = 20;
  TwoViewOptions o = options_.mono_init.two_view;
  o.min_points = std::min(o.min_points, kBridgeMinPoints);
  return o;
}

std::optional<Pose> SlidingWindowEstimator::BridgeFromLastKeyframe(const FrameMeasurement& m,
                                                                   std::string* note,
                                                                   std::string* why_not) const {
  if (!options_.mono_bridge || !last_keyframe_.valid() || !last_tracked_ ||
      !keyframe_poses_.count(last_keyframe_)) {
    return std::nullopt;
  }
  const int64_t t_kf = frames_.at(first_frame_of_keyframe_.at(last_keyframe_)).t_ns;
  const double distance =
      last_tracked_->velocity_w.norm() * 1e-9 * static_cast<double>(m.t_ns - t_kf);
  // Over the frame's own tracks: not the observations a loop relabelled (see Add).
  FrameMeasurement own = m;
  own.observations.erase(std::remove_if(own.observations.begin(), own.observations.end(),
                                        [&](const FeatureObservation& o) {
                                          return unconfirmed_loop_landmarks_.count(o.landmark) > 0;
                                        }),
                         own.observations.end());
  std::string why;
  const std::optional<KeyframeBridge> bridge =
      BridgeFromKeyframe(rig_.left, KeyframePoseNow(last_keyframe_), last_keyframe_observations_,
                         own, distance, BridgeTwoViewOptions(), &why);
  if (!bridge) {
    std::ostringstream os;
    os << ", no bridge from keyframe " << last_keyframe_ << " (" << why << ")";
    *why_not += os.str();
    VLOG(1) << "frame " << m.frame << os.str();
    return std::nullopt;
  }
  std::ostringstream os;
  os.precision(3);
  os << "bridged from keyframe " << last_keyframe_ << " (too few mapped landmarks: the two-view "
     << "geometry of " << bridge->num_points << " points, median parallax "
     << bridge->median_parallax_deg << " deg; the step's length from the last speed)";
  *note = os.str();
  VLOG(1) << "frame " << m.frame << ": " << *note;
  return bridge->T_w_cur;
}

void SlidingWindowEstimator::ReportLandmarks(EstimatorOutput* out) const {
  // Called while no window solve runs: the window's landmarks at their current estimates.
  const std::map<LandmarkId, Eigen::Vector3d> landmarks = ba_.Landmarks();
  out->landmarks_in_state = static_cast<int>(landmarks.size());
  out->local_map.assign(landmarks.begin(), landmarks.end());
  // The frontend tracks a fused point under its newer id: that id is in the local map too.
  if (fused_from_.empty()) return;
  for (const auto& [id, p_w] : landmarks) {
    const auto [first, last] = fused_from_.equal_range(id);
    for (auto it = first; it != last; ++it) out->local_map.emplace_back(it->second, p_w);
  }
}

Pose SlidingWindowEstimator::PredictPose(const FrameMeasurement& m) const {
  Pose velocity = velocity_;
  if (m.motion) {
    if (rig_.is_stereo()) {
      velocity = m.motion->T_prev_cur;
    } else {
      // The essential matrix's rotation, the constant velocity's translation (no scale).
      velocity.linear() = m.motion->T_prev_cur.linear();
    }
  }
  return Orthonormalized(T_w_prev_ * velocity);
}

void SlidingWindowEstimator::NoteMonoTracking(const FrameMeasurement& m, bool valid,
                                              const Pose& T_w_c, EstimatorOutput* out) {
  if (valid) {
    if (last_tracked_ && m.t_ns > last_tracked_->t_ns) {
      last_tracked_->velocity_w = (T_w_c.translation() - last_tracked_->T_w_c.translation()) /
                                  (1e-9 * static_cast<double>(m.t_ns - last_tracked_->t_ns));
    }
    // Not emplace(): clang cannot default-construct a nested struct with member initializers
    // inside std::optional while the enclosing class is incomplete (its DALA_FUZZ build).
    if (!last_tracked_) last_tracked_ = Reinit();
    last_tracked_->t_ns = m.t_ns;
    last_tracked_->T_w_c = T_w_c;
    lost_streak_ = 0;
    return;
  }
  // A lost mono frame has no pose: its prediction has no scale to trust.
  frames_.back().has_pose = false;
  if (++lost_streak_ < options_.mono_reinit_after_lost_frames || !last_tracked_) return;
  // Lost too long for the map to come back into view: a new map, continued from the old one
  // (PlaceReinitializedMap). The old landmarks keep their positions (PnP recovery and loop
  // closure can still use them); the window starts empty.
  // The old window stays until the new map starts (StartMonoMap), so that a frame that
  // relocalises in the old map first (ResumeOldMap) continues in it.
  reinit_ = *last_tracked_;
  initializer_.emplace(rig_.left, options_.mono_init);
  lost_streak_ = 0;
  out->note = "lost for " + std::to_string(options_.mono_reinit_after_lost_frames) +
              " frames: re-initialising a new map";
  VLOG(1) << "frame " << m.frame << ": " << out->note;
}

EstimatorOutput SlidingWindowEstimator::AddBeforeInitialization(const FrameMeasurement& m) {
  const std::optional<MonoInitialization> init = initializer_->Add(m);
  EstimatorOutput out;
  if (!init) {
    frames_.push_back({m.t_ns, KeyframeId(), Pose::Identity(), /*has_pose=*/false});
    // A re-initialisation after a loss: these frames are lost (tracking failures), not the
    // start of the run; the old map is still handed over, so that the frontend keeps trying to
    // relocalise in it.
    out.initializing = !reinit_.has_value();
    out.note = std::string(reinit_ ? "lost, re-initialising: " : "initialising: ") +
               initializer_->reason();
    if (reinit_) {
      out.T_w_c = T_w_prev_;
      ReportLandmarks(&out);
    }
    return out;
  }
  const std::string note = StartMapFrom(*init, /*current_reported=*/init->next.has_value());
  if (init->next) {
    // The checking frame is tracked in the new map as any frame after it (initializer_ is
    // spent: Add does not come back here).
    EstimatorOutput next = Add(*init->next);
    next.note = note + "; checked by frame " + std::to_string(m.frame.value) +
                (next.note.empty() ? "" : "; " + next.note);
    return next;
  }
  out.valid = true;
  out.T_w_c = T_w_prev_;
  ReportLandmarks(&out);
  out.note = note;
  return out;
}

std::string SlidingWindowEstimator::StartMapFrom(const MonoInitialization& init,
                                                bool current_reported) {
  if (current_reported) {
    // A pair checked by a later frame (or still waiting at the end of the run): its current
    // frame was reported initialising, the last so far; that record goes, StartMonoMap writes
    // it again with the map.
    CHECK(!frames_.empty() && frames_.back().t_ns == init.current.t_ns);
    frames_.pop_back();
  }
  const bool reinitialised = reinit_.has_value();
  if (reinitialised) {
    // The new map starts in a window of its own; the old landmarks keep their positions (PnP
    // recovery and loop closure can still use them).
    RestartWindow();
  }
  const int placed_before_reference = StartMonoMap(init);
  initializer_.reset();
  reinit_.reset();
  std::ostringstream note;
  note.precision(3);
  note << (reinitialised ? "re-initialised (a new map placed at the extrapolated pose with the "
                           "last speed: scale and heading across the gap are guesses) "
                         : "initialised ")
       << "from frame " << init.reference.frame << " (" << init.p_ref.size() << " points, "
       << init.ModelName() << ", median parallax " << init.two_view.median_parallax_deg
       << " deg)";
  if (placed_before_reference > 0) {
    note << "; " << placed_before_reference << " earlier frames placed in it";
  }
  VLOG(1) << "frame " << init.current.frame << ": " << note.str();
  return note.str();
}

Sim3 SlidingWindowEstimator::PlaceReinitializedMap(const MonoInitialization& init) const {
  // The reference camera at the last tracked pose moved on at the last velocity (world frame,
  // per second), the heading kept; the new map's unit (the two-view baseline) is the distance
  // the last speed covers between the two views.
  const Reinit& r = *reinit_;
  const double to_reference = 1e-9 * static_cast<double>(init.reference.t_ns - r.t_ns);
  const double pair = 1e-9 * static_cast<double>(init.current.t_ns - init.reference.t_ns);
  Sim3 S;
  S.T = r.T_w_c;
  S.T.translation() += r.velocity_w * to_reference;
  S.scale = std::max(r.velocity_w.norm() * pair, 1e-6);
  return S;
}

int SlidingWindowEstimator::StartMonoMap(const MonoInitialization& init) {
  const size_t current_index = frames_.size();
  const size_t reference_index = current_index - init.between.size() - 1;
  CHECK_EQ(frames_.at(reference_index).t_ns, init.reference.t_ns);
  // World = the reference camera; after a loss, the map placed where the old one would be.
  const Sim3 S_w_ref = reinit_ ? PlaceReinitializedMap(init) : Sim3();
  const Pose T_w_ref = S_w_ref.T;
  const Pose T_w_cur = (S_w_ref * Sim3{init.T_ref_cur, 1.0}).T;
  for (const auto& [id, p_ref] : init.p_ref) ba_.SetLandmarkPosition(id, S_w_ref * p_ref);
  const auto make_keyframe = [&](const FrameMeasurement& f, const Pose& T_w_c) {
    BaKeyframe kf;
    kf.id = KeyframeId(num_keyframes_++);
    kf.t_ns = f.t_ns;
    kf.T_w_c = T_w_c;
    for (const FeatureObservation& o : f.observations) {
      if (!init.p_ref.count(o.landmark)) continue;
      kf.observations.push_back(AsKeyframeObservation(o));
      ++landmark_observations_[o.landmark];
    }
    AddToWindow(kf, f);
    keyframe_poses_[kf.id] = T_w_c;
    keyframe_of_frame_[f.frame] = kf.id;
    return kf.id;
  };
  const KeyframeId reference = make_keyframe(init.reference, T_w_ref);
  const KeyframeId current = make_keyframe(init.current, T_w_cur);
  for (const auto& [id, p_ref] : init.p_ref) anchor_.emplace(id, reference);
  frames_[reference_index] = {init.reference.t_ns, reference, Pose::Identity(), true};
  SolveWindow(current);

  const int placed_before_reference = PlaceEarlierFrames(init, reference_index, reference, current);
  // The frames between the two views, localised in the new map (their guess: interpolated).
  const double span = static_cast<double>(init.current.t_ns - init.reference.t_ns);
  std::optional<Pose> T_w_last;
  for (size_t j = 0; j < init.between.size(); ++j) {
    const FrameMeasurement& f = init.between[j];
    const double s = span > 0 ? (f.t_ns - init.reference.t_ns) / span : 0.5;
    const Pose guess =
        InterpolatePose(keyframe_poses_.at(reference), keyframe_poses_.at(current), s);
    const PoseOnlyResult r = ba_.TrackFrame(WindowObservations(f), guess, options_.pose_only);
    if (r.status != PoseOnlyStatus::kOk) {
      T_w_last.reset();
      continue;
    }
    frames_[reference_index + 1 + j] = {f.t_ns, reference,
                                        keyframe_poses_.at(reference).inverse() * r.T_w_c, true};
    DeferFrameRefinement(reference_index + 1 + j, f);
    T_w_last = r.T_w_c;
  }
  // The current keyframe's first frame (the bridge times its step from it). The reference has none
  // (the earlier frames placed before it refer to it); neither pair keyframe is ever culled.
  first_frame_of_keyframe_[current] = frames_.size();
  frames_.push_back({init.current.t_ns, current, Pose::Identity(), true});
  T_w_prev_ = keyframe_poses_.at(current);
  RememberLastKeyframe(reference, init.reference);  // Its tracks: views of new landmarks too.
  // The velocity: from the frame before when it was localised, else the mean over the span.
  velocity_ = T_w_last ? T_w_last->inverse() * T_w_prev_
                       : InterpolatePose(Pose::Identity(), T_w_prev_,
                                         1.0 / static_cast<double>(init.between.size() + 1));
  RememberLastKeyframe(current, init.current);
  // The pair's current frame is the map's last tracked frame, moving at the pair's mean velocity
  // (world frame, per second): the keyframe bridge takes a lost frame's step length from it and
  // the re-initialisation after mono_reinit_after_lost_frames places the new map from it, so a
  // map whose pair the next frames do not find again is bridged or re-initialised like any other.
  Reinit tracked;
  tracked.t_ns = init.current.t_ns;
  tracked.T_w_c = T_w_prev_;
  const double pair_s = 1e-9 * static_cast<double>(init.current.t_ns - init.reference.t_ns);
  if (pair_s > 0) {
    tracked.velocity_w =
        (T_w_prev_.translation() - keyframe_poses_.at(reference).translation()) / pair_s;
  }
  last_tracked_ = tracked;
  return placed_before_reference;
}

int SlidingWindowEstimator::PlaceEarlierFrames(const MonoInitialization& init,
                                               size_t reference_index, KeyframeId reference,
                                               KeyframeId current) {
  // Only the first map: after a loss, the frames before the new reference stay lost.
  if (reinit_) return 0;
  // Back from the reference, each guessed by the pair's motion at its time (constant velocity),
  // tracked against the new map; the first that fails ends it (the earlier ones share fewer
  // of the new map's landmarks).
  const Pose& T_w_ref = keyframe_poses_.at(reference);
  const double span = static_cast<double>(init.current.t_ns - init.reference.t_ns);
  std::vector<std::pair<size_t, const FrameMeasurement*>> placed;  // Latest first.
  size_t index = reference_index;
  for (auto f = init.earlier.rbegin(); f != init.earlier.rend(); ++f) {
    while (index > 0 && frames_[index].t_ns != f->t_ns) --index;
    if (frames_[index].t_ns != f->t_ns || frames_[index].has_pose) break;
    const double s = span > 0 ? (f->t_ns - init.reference.t_ns) / span : 0.0;
    const Pose guess = InterpolatePose(T_w_ref, keyframe_poses_.at(current), s);
    const PoseOnlyResult r = ba_.TrackFrame(WindowObservations(*f), guess, options_.pose_only);
    if (r.status != PoseOnlyStatus::kOk) break;
    frames_[index] = {f->t_ns, reference, T_w_ref.inverse() * r.T_w_c, true};
    placed.emplace_back(index, &*f);
  }
  // Their later refinement in time order, before the frames between the pair.
  for (auto it = placed.rbegin(); it != placed.rend(); ++it) {
    DeferFrameRefinement(it->first, *it->second);
  }
  return static_cast<int>(placed.size());
}

void SlidingWindowEstimator::RememberLastKeyframe(KeyframeId id, const FrameMeasurement& m) {
  // The previous last keyframe's observations join the earlier ones; those of keyframes that
  // have left the window are forgotten (a new landmark's views must be window keyframes).
  if (last_keyframe_.valid() && last_keyframe_ != id) {
    earlier_keyframe_observations_[last_keyframe_] = std::move(last_keyframe_observations_);
  }
  for (auto it = earlier_keyframe_observations_.begin();
       it != earlier_keyframe_observations_.end();) {
    it = ba_.KeyframePose(it->first) ? std::next(it) : earlier_keyframe_observations_.erase(it);
  }
  last_keyframe_ = id;
  last_keyframe_observations_.clear();
  for (const FeatureObservation& o : m.observations) {
    last_keyframe_observations_[o.landmark] = AsKeyframeObservation(o);
  }
}

void SlidingWindowEstimator::AddToWindow(const BaKeyframe& kf, const FrameMeasurement& m) {
  ba_.AddKeyframe(kf);
  // What Refine solves, kept only when it will run (~48 B per observation: ~15 MB over the
  // 1,300 keyframes of a 3,000-frame rover run).
  if (KeepsObservationArchive()) {
    for (const FeatureObservation& o : m.observations) {
      if (!unconfirmed_loop_landmarks_.count(o.landmark)) {
        observation_archive_.emplace_back(kf.id, AsKeyframeObservation(o));
      }
    }
  }
  // The window's gauge (SlidingWindowBa: num_fixed_keyframes, -1 => 1 stereo, 2 mono).
  const int num_fixed = options_.ba.num_fixed_keyframes >= 0 ? options_.ba.num_fixed_keyframes
                                                             : (rig_.is_stereo() ? 1 : 2);
  // Refine's gauge: a stereo window's first keyframe held; a mono one's first keyframe held and
  // its distance to the second (the unit), the rest of the second pose free (7 dof).
  const bool stereo = rig_.is_stereo();
  if (added_since_window_start_ == 0 || (stereo && added_since_window_start_ < num_fixed)) {
    gauge_keyframes_.insert(kf.id);
  } else if (!stereo && added_since_window_start_ == 1) {
    const KeyframeId first = *gauge_keyframes_.rbegin();
    unit_pairs_.push_back({first, kf.id});
  }
  ++added_since_window_start_;
}

void SlidingWindowEstimator::RestartWindow() {
  WaitForWindowSolve();
  added_since_window_start_ = 0;
  const DisparityOffsetCalibration calibration = ba_.offset_calibration();
  ba_ = SlidingWindowBa(IntrinsicsOf(rig_, ba_.disparity_offset_px()), options_.ba);
  ba_.set_offset_calibration(calibration);
  for (const auto& [id, p_w] : map_points_) ba_.SetLandmarkPosition(id, p_w);
  // The last keyframe left with the old window: its observations can pair with none of the new
  // window's keyframes (mono new landmarks, SelectKeyframeObservations).
  last_keyframe_observations_.clear();
  earlier_keyframe_observations_.clear();
}

std::optional<Pose> SlidingWindowEstimator::ResumeOldMap(const FrameMeasurement& m) {
  std::optional<Pose> T_w_c = RecoverPose(m);
  if (!T_w_c) return std::nullopt;
  initializer_.reset();
  reinit_.reset();
  VLOG(1) << "frame " << m.frame << ": relocalised in the old map; the re-initialisation stops";
  return T_w_c;
}

void SlidingWindowEstimator::CullHeldKeyframes() {
  if (held_by_.empty()) return;
  std::set<KeyframeId> in_use;  // The window's keyframes and those it holds constant.
  for (const KeyframeId k : ba_.WindowKeyframes()) in_use.insert(k);
  for (const KeyframeId k : ba_.HeldKeyframes()) in_use.insert(k);
  for (auto it = held_by_.begin(); it != held_by_.end();) {
    const auto [culled, holder] = *it;
    if (in_use.count(culled)) {
      ++it;
      continue;
    }
    // Never a gauge keyframe (Refine holds it; a mono map's unit pair fixes its scale), never a
    // holder gone (holders store a place entry, so they are never culled themselves).
    bool keep = gauge_keyframes_.count(culled) > 0 || !keyframe_poses_.count(holder) ||
                !keyframe_poses_.count(culled);
    for (const auto& [a, b] : unit_pairs_) keep = keep || a == culled || b == culled;
    if (!keep) CullKeyframe(culled, holder);
    it = held_by_.erase(it);
  }
}

void SlidingWindowEstimator::CullKeyframe(KeyframeId culled, KeyframeId holder) {
  const Pose T_holder_culled = keyframe_poses_.at(holder).inverse() * keyframe_poses_.at(culled);
  // Its frames: from its own to the first of a later keyframe (frames are in time order and
  // refer to the keyframe before them, or to a holder, which is older).
  const auto first = first_frame_of_keyframe_.find(culled);
  for (size_t i = first == first_frame_of_keyframe_.end() ? 0 : first->second; i < frames_.size();
       ++i) {
    FrameRecord& f = frames_[i];
    if (f.reference == culled) {
      f.reference = holder;
      f.T_kf_c = T_holder_culled * f.T_kf_c;
    } else if (f.reference.valid() && culled < f.reference) {
      break;
    }
  }
  if (first != first_frame_of_keyframe_.end()) first_frame_of_keyframe_.erase(first);
  MergeIntoHolder(culled, holder);  // Before its pose goes.
  keyframe_poses_.erase(culled);
  for (auto it = keyframe_of_frame_.begin(); it != keyframe_of_frame_.end(); ++it) {
    if (it->second == culled) {
      keyframe_of_frame_.erase(it);
      break;
    }
  }
  observation_archive_.erase(
      std::remove_if(observation_archive_.begin(), observation_archive_.end(),
                     [&](const auto& o) { return o.first == culled; }),
      observation_archive_.end());
  // Its landmarks: those the window still uses move with the holder from now on, the others
  // are forgotten.
  const std::map<LandmarkId, Eigen::Vector3d> window = ba_.Landmarks();
  std::vector<LandmarkId> forgotten;
  for (auto it = anchor_.begin(); it != anchor_.end();) {
    if (it->second != culled) {
      ++it;
    } else if (window.count(it->first)) {
      it->second = holder;
      ++it;
    } else {
      forgotten.push_back(it->first);
      map_points_.erase(it->first);
      landmark_observations_.erase(it->first);
      unconfirmed_loop_landmarks_.erase(it->first);
      it = anchor_.erase(it);
    }
  }
  ba_.ForgetLandmarks(forgotten);
  VLOG(2) << "keyframe " << culled << " culled (its place is held by keyframe " << holder << "), "
          << forgotten.size() << " landmarks forgotten";
}

bool SlidingWindowEstimator::OutsideWindow(const FrameMeasurement& m) const {
  // The window's landmarks seen by m against the older ones (positions outside the window).
  const std::map<LandmarkId, Eigen::Vector3d> window = ba_.Landmarks();
  int inside = 0, outside = 0;
  for (const FeatureObservation& o : m.observations) {
    if (window.count(o.landmark)) {
      ++inside;
    } else if (ba_.LandmarkPosition(o.landmark) && !unconfirmed_loop_landmarks_.count(o.landmark)) {
      ++outside;
    }
  }
  const int enough = 2 * options_.pose_only.min_inliers;
  return inside < enough && outside >= enough;
}

EstimatorOutput SlidingWindowEstimator::Add(const FrameMeasurement& measurement) {
  WaitForWindowSolve();
  // Landmark fusion renamed some of the frontend's ids (RenameFused).
  const FrameMeasurement renamed =
      fused_into_.empty() ? FrameMeasurement() : WithFusedIds(measurement);
  const FrameMeasurement& m = fused_into_.empty() ? measurement : renamed;
  if (solved_in_background_) {
    T_w_prev_ = keyframe_poses_.at(*solved_in_background_);
    solved_in_background_.reset();
  }
  // The offset this frame is tracked with; read here, while no window solve runs (one started
  // below may change it in the background: SlidingWindowBa calibrates it).
  const double disparity_offset_px = ba_.disparity_offset_px();
  RefineWaitingFrames(/*all=*/false);  // Before culling: a culled keyframe left the window.
  CullHeldKeyframes();
  // Lost for long (mono): a frame that relocalises in the old map resumes it; else the new
  // map's initialisation goes on.
  std::optional<Pose> resumed;
  if (initializer_ && reinit_) resumed = ResumeOldMap(m);
  // In a saved map (UseMap): the first frame placed in it starts the run there.
  std::optional<Pose> T_w_start;
  if (awaiting_map_) {
    T_w_start = RecoverPose(m);
    if (!T_w_start) {
      frames_.push_back({m.t_ns, KeyframeId(), Pose::Identity(), /*has_pose=*/false});
      EstimatorOutput out;
      out.initializing = true;
      out.note = "localising in the saved map: no mapped place recognised yet";
      return out;
    }
    awaiting_map_ = false;
    initializer_.reset();
  }
  if (initializer_) return AddBeforeInitialization(m);
  const bool stereo = rig_.is_stereo();
  EstimatorOutput out;
  // Initial guess: the previous estimate moved by the visual motion (or the last velocity).
  // The first keyframe: stereo's first frame, or the first frame placed in a saved map (mono
  // starts in AddBeforeInitialization otherwise).
  const bool first = num_keyframes_ == 0;
  if (stereo && !first && m.motion) velocity_ = m.motion->T_prev_cur;
  Pose T_w_c = first ? T_w_start.value_or(Pose::Identity()) : PredictPose(m);
  const Pose T_w_predicted = T_w_c;
  out.valid = first || (stereo && m.motion.has_value());
  if (T_w_start) out.note = "localised in the saved map";

  std::string why_lost;  // Filled as each way of placing the frame fails.
  // One camera, a loop detected at this keyframe: the observations the frontend relabelled with
  // the old landmarks' ids are the loop's to judge (CloseMonoLoop), not this frame's. Placed by
  // them, the frame would already sit in the old neighbourhood, and the loop, right or wrong,
  // would turn it by nothing (the orientation gate would measure nothing). Refused, the frame
  // keeps those points under the ids the current map knows them by (`before_loop`; the frontend
  // gives them back too: Frontend::ReturnLoopIds), so that the refusal costs it nothing.
  const bool mono_loop = !stereo && !first && m.is_keyframe && m.loop && options_.loop.enable;
  if (mono_loop) {
    for (const auto& ids : m.loop->relabelled) unconfirmed_loop_landmarks_.insert(ids.second);
  }
  std::string loop_not_closed;  // Why a detected loop was not closed (the frame's note).
  bool placed_by_window = false;  // By the pose-only tracking against the window.
  bool recovered_here = false;    // By RecoverPose (relocalised_ set for it).
  if (!first) {
    if (stereo && m.is_keyframe && m.loop && options_.loop.enable) {
      out.loop_closed = CloseLoop(*m.loop, KeyframeId(num_keyframes_), &T_w_c, &loop_not_closed);
    }
    // Pose-only tracking against the window (a keyframe: before it joins the window); a frame
    // that resumed the old map has its pose already.
    const std::vector<BaObservation> mapped = WindowObservations(m);
    const PoseOnlyResult r =
        resumed ? PoseOnlyResult() : ba_.TrackFrame(mapped, T_w_c, options_.pose_only);
    VLOG(r.status == PoseOnlyStatus::kOk ? 2 : 1)
        << "frame " << m.frame << ": pose-only " << PoseOnlyStatusName(r.status) << ", "
        << r.num_inliers << " inliers of " << mapped.size() << " observations of mapped landmarks";
    if (r.status == PoseOnlyStatus::kOk) {
      T_w_c = r.T_w_c;
      out.valid = true;
      placed_by_window = true;
    } else if (!resumed) {
      std::ostringstream why;
      why << "lost: tracking against the window " << PoseOnlyStatusName(r.status) << " ("
          << r.num_inliers << " inliers of " << mapped.size()
          << " observations of mapped landmarks)";
      why_lost = why.str();
    }
  }
  if (!out.valid && !first) {
    if (const std::optional<Pose> recovered = resumed ? resumed : RecoverPose(m)) {
      T_w_c = *recovered;
      out.valid = true;
      relocalised_ = true;
      recovered_here = !resumed;
    } else {
      why_lost += ", the PnP recovery on every mapped landmark failed";
    }
  }
  // A bridged frame: the keyframe it was bridged from and T_kf_cur (a prior if it becomes one).
  std::optional<std::pair<KeyframeId, Pose>> bridged_from;
  if (!out.valid && !first && !stereo) {
    if (const std::optional<Pose> bridged = BridgeFromLastKeyframe(m, &out.note, &why_lost)) {
      T_w_c = *bridged;
      out.valid = true;
      bridged_from.emplace(last_keyframe_, KeyframePoseNow(last_keyframe_).inverse() * *bridged);
    }
  }
  // Why a frame has no pose (report.json's note); a later note (a new map starts) replaces it.
  if (!out.valid && !first && out.note.empty()) out.note = why_lost;
  // One camera: the loop closes from the tracked pose (the similarity moves it). When only the
  // loop's observations could place the frame, the loop is judged from the constant-velocity
  // prediction instead (the gate measures the turn from it); closed, it places the frame.
  if (mono_loop) {
    if (out.valid) {
      out.loop_closed = CloseMonoLoop(m, KeyframeId(num_keyframes_), &T_w_c, &loop_not_closed);
    } else {
      Pose T_w_loop = T_w_predicted;
      if (CloseMonoLoop(m, KeyframeId(num_keyframes_), &T_w_loop, &loop_not_closed)) {
        T_w_c = T_w_loop;
        out.valid = true;
        out.loop_closed = true;
        out.note = "placed by the loop closure to frame " +
                   std::to_string(m.loop->old_frame.value) +
                   " (the current map alone could not place it)";
      }
    }
    // Unless the loop closes, the old landmarks' estimates are outliers of the drifted
    // neighbourhood: they stay unconfirmed (set above), and the frontend gives the points their
    // ids back (loop_refused), so that the next frames observe the current landmarks again. A
    // loop that closes confirms the old landmarks, also those an earlier refused loop had
    // relabelled.
    if (out.loop_closed) {
      for (const auto& ids : m.loop->relabelled) unconfirmed_loop_landmarks_.erase(ids.second);
    }
    out.loop_refused = !out.loop_closed;
  }
  // What the frame keeps: the old ids where its loop closed, the current map's where it did not
  // (the frontend's ids: landmark fusion renames them after the ids before the loop are back).
  const FrameMeasurement before_loop = !out.loop_refused ? FrameMeasurement()
                                       : fused_into_.empty()
                                           ? WithIdsBeforeLoop(m)
                                           : WithFusedIds(WithIdsBeforeLoop(measurement));
  const FrameMeasurement& kept = out.loop_refused ? before_loop : m;
  // Refused where the frame's other points could not place it against the window (the loop
  // relabelled most of its mapped ones): placed by all of them under their current ids, rather
  // than by the PnP recovery or the bridge, or not at all.
  if (out.loop_refused && !placed_by_window && !resumed) {
    const std::vector<BaObservation> mapped = WindowObservations(before_loop);
    const PoseOnlyResult r = ba_.TrackFrame(mapped, T_w_predicted, options_.pose_only);
    if (r.status == PoseOnlyStatus::kOk) {
      T_w_c = r.T_w_c;
      out.valid = true;
      out.note.clear();  // Why it was lost, or how it was bridged.
      bridged_from.reset();
      if (recovered_here) relocalised_ = false;
    }
  }
  // A mono keyframe needs a tracked pose (see the class comment).
  const bool new_keyframe = first || (m.is_keyframe && (stereo || out.valid));
  if (new_keyframe && out.valid && relocalised_) {
    // The first keyframe after a relocalisation: placed by the old landmarks it sees again
    // (RecoverPose). When those lie outside the window (a place mapped long ago, found by the
    // place recognition after a long loss), nothing links the keyframe to the window's
    // keyframes: the window starts again from it, held as the gauge at its relocalised pose.
    relocalised_ = false;
    if (OutsideWindow(kept)) {
      RestartWindow();
      out.note = "relocalised in the map (a place seen before); the window starts again here";
      VLOG(1) << "frame " << m.frame << ": " << out.note;
    }
  }
  if (new_keyframe) {
    BaKeyframe kf;
    kf.id = KeyframeId(num_keyframes_++);
    kf.t_ns = m.t_ns;
    kf.T_w_c = T_w_c;
    kf.observations = SelectKeyframeObservations(kept, T_w_c);
    AddToWindow(kf, kept);
    // A bridged keyframe keeps the bridge's relative pose as a prior while its own landmarks
    // are new (SlidingWindowBa::AddRelativePosePrior); a loop closed here moved it since.
    if (bridged_from && !out.loop_closed && ba_.KeyframePose(bridged_from->first)) {
      ba_.AddRelativePosePrior(bridged_from->first, kf.id, bridged_from->second,
                               BridgeInformation(bridged_from->second));
    }
    keyframe_poses_[kf.id] = T_w_c;
    first_frame_of_keyframe_[kf.id] = frames_.size();
    frames_.push_back({m.t_ns, kf.id, Pose::Identity()});
    keyframe_of_frame_[m.frame] = kf.id;
    if (options_.cull_held_keyframes && m.place_held_by &&
        !PlaceReleasedByRefusedLoop(m, out.loop_refused)) {
      const auto holder = keyframe_of_frame_.find(*m.place_held_by);
      if (holder != keyframe_of_frame_.end()) held_by_[kf.id] = holder->second;
    }
    if (!stereo) RememberLastKeyframe(kf.id, kept);
    ReportLandmarks(&out);
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
    if (out.valid) DeferFrameRefinement(frames_.size() - 1, kept);
    ReportLandmarks(&out);
  }
  // After lost frames T_w_prev_ is a guess: the last tracked velocity is kept.
  if (!stereo && out.valid && !resumed && !first) {
    velocity_ = T_w_prev_.inverse() * T_w_c;
  }
  T_w_prev_ = T_w_c;
  out.T_w_c = T_w_c;
  out.keyframes_in_map = num_keyframes_in_map();
  if (stereo) out.disparity_offset_px = disparity_offset_px;
  if (!stereo) NoteMonoTracking(kept, out.valid, T_w_c, &out);
  if (!loop_not_closed.empty()) {
    out.loop_not_closed = loop_not_closed;
    const std::string loop_note = "loop to frame " + std::to_string(m.loop->old_frame.value) +
                                  " not closed: " + loop_not_closed;
    out.note = out.note.empty() ? loop_note : out.note + "; " + loop_note;
  }
  // A lost stereo frame has no pose either: it would be an extrapolation (a lost keyframe still
  // joins the window at that guess, to carry the stereo landmarks it starts).
  if (stereo && !out.valid) frames_.back().has_pose = false;
  return out;
}

Trajectory SlidingWindowEstimator::trajectory() const {
  WaitForWindowSolve();
  Trajectory t;
  t.poses.reserve(frames_.size());
  for (const FrameRecord& f : frames_) {
    if (f.has_pose) t.Add(f.t_ns, KeyframePoseNow(f.reference) * f.T_kf_c);
  }
  return t;
}

bool SlidingWindowEstimator::UseMap(const std::vector<MapPoint>& landmarks) {
  CHECK(frames_.empty()) << "UseMap before the first frame";
  for (const MapPoint& p : landmarks) {
    ba_.SetLandmarkPosition(p.id, p.p_w);
    map_points_[p.id] = p.p_w;
    // Known landmarks: a keyframe that sees one takes the observation (SelectKeyframeObservations).
    landmark_observations_[p.id] = std::max(p.observations, 1);
  }
  awaiting_map_ = true;
  return true;
}

std::optional<double> SlidingWindowEstimator::DisparityOffsetPx() const {
  if (!rig_.is_stereo()) return std::nullopt;
  WaitForWindowSolve();
  return ba_.disparity_offset_px();
}

std::string SlidingWindowEstimator::DisparityOffsetNote() const {
  if (!rig_.is_stereo()) return {};
  WaitForWindowSolve();
  std::ostringstream os;
  os << std::fixed << std::setprecision(3) << ba_.disparity_offset_px() << " px";
  const SlidingWindowBa::Options& o = options_.ba;
  if (o.estimate_disparity_offset) {
    os << ", estimated in every window (ba.estimate_disparity_offset)";
    return os.str();
  }
  if (!o.calibrate_disparity_offset) {
    os << ", fixed (ba.calibrate_disparity_offset is off; ba.disparity_offset_px)";
    return os.str();
  }
  const DisparityOffsetCalibration& c = ba_.offset_calibration();
  if (online_offset_px_) {
    os << ", estimated with every keyframe by the global BA after the run (online calibration: "
       << *online_offset_px_ << " px from " << c.num_estimates() << " windows)";
  } else if (ba_.disparity_offset_px() != 0.0) {
    os << ", calibrated online from " << c.num_estimates() << " windows (median " << std::showpos
       << c.median_px() << std::noshowpos << " px, weight " << std::setprecision(2) << c.weight()
       << ")";
  } else if (c.num_estimates() < o.offset_calibration.min_estimates) {
    os << ": not calibrated, " << c.num_estimates() << " windows with enough motion (needs "
       << o.offset_calibration.min_estimates << ")";
  } else {
    os << ": the " << c.num_estimates() << " windows' median estimate " << std::showpos
       << c.median_px() << std::noshowpos
       << " px is within what an exact rig shows (|median| <= " << o.offset_calibration.bias_px
       << " px): none applied";
  }
  if (!online_offset_px_ && !c.converged() && c.num_estimates() > 0) os << " (still calibrating)";
  if (ba_.disparity_offset_px() != 0.0) {
    // In the form that gives it to a later run of the same rig.
    os << "; for later runs of this rig: --set ba.calibrate_disparity_offset=0 --set "
          "ba.disparity_offset_px="
       << std::setprecision(3) << ba_.disparity_offset_px();
  }
  return os.str();
}

bool SlidingWindowEstimator::CalibratesRigOffset() const {
  return rig_.is_stereo() && options_.ba.calibrate_disparity_offset &&
         !options_.ba.estimate_disparity_offset;
}

bool SlidingWindowEstimator::KnowsRigOffset() const {
  return rig_.is_stereo() && !options_.ba.calibrate_disparity_offset &&
         !options_.ba.estimate_disparity_offset && options_.ba.disparity_offset_px != 0.0;
}

bool SlidingWindowEstimator::KeepsObservationArchive() const {
  if (options_.final_ba == "off") return false;
  return options_.final_ba != "rig_offset" || CalibratesRigOffset() || KnowsRigOffset();
}

bool SlidingWindowEstimator::RigHasOffset() const {
  return (CalibratesRigOffset() || KnowsRigOffset()) && ba_.disparity_offset_px() != 0.0;
}

void SlidingWindowEstimator::DeferFrameRefinement(size_t index, const FrameMeasurement& m) {
  const std::string& when = options_.refine_frames;
  if (when == "off" || (when == "mono" && rig_.is_stereo())) return;
  WaitingFrame waiting;
  waiting.index = index;
  for (const FeatureObservation& o : m.observations) {
    if (!unconfirmed_loop_landmarks_.count(o.landmark)) {
      waiting.observations.push_back(AsFrameObservation(o));
    }
  }
  waiting_frames_.push_back(std::move(waiting));
  if (waiting_frames_.size() > kMaxWaitingFrames) {
    // The oldest now, its keyframe still in the window: with the estimates of this moment.
    RefineFrame(waiting_frames_.front());
    waiting_frames_.pop_front();
  }
}

void SlidingWindowEstimator::RefineWaitingFrames(bool all) {
  if (waiting_frames_.empty()) return;
  const std::vector<KeyframeId> ids = ba_.WindowKeyframes();
  const std::set<KeyframeId> window(ids.begin(), ids.end());
  // Frames are in time order, and so are their keyframes (culling moves a frame to an older
  // holder, which has left the window too): the first frame still in the window ends the pass.
  while (!waiting_frames_.empty()) {
    if (!all && window.count(frames_.at(waiting_frames_.front().index).reference)) break;
    RefineFrame(waiting_frames_.front());
    waiting_frames_.pop_front();
  }
}

void SlidingWindowEstimator::RefineFrame(const WaitingFrame& waiting) {
  FrameRecord& f = frames_.at(waiting.index);
  if (!f.has_pose || !f.reference.valid() || !keyframe_poses_.count(f.reference)) return;
  const Pose T_w_kf = KeyframePoseNow(f.reference);
  const PoseOnlyResult r = EstimatePoseOnly(
      IntrinsicsOf(rig_, ba_.disparity_offset_px()), waiting.observations,
      [&](LandmarkId id) -> std::optional<Eigen::Vector3d> {
        if (unconfirmed_loop_landmarks_.count(id)) return std::nullopt;
        const auto it = map_points_.find(id);
        if (it == map_points_.end()) return std::nullopt;
        return it->second;
      },
      T_w_kf * f.T_kf_c, options_.pose_only);
  if (r.status == PoseOnlyStatus::kOk) f.T_kf_c = T_w_kf.inverse() * r.T_w_c;
}

RefinementSummary SlidingWindowEstimator::Refine(const std::function<bool()>& stop_requested) {
  WaitForWindowSolve();
  // One camera: a pair (the first map's, or a new map's after a loss) found at the last frame
  // had no next frame to check it; the map starts from it unchecked, so that its frames have
  // poses rather than none. Only here: a run that never calls Refine (an interrupted one)
  // leaves those frames without a pose, and the online trajectory taken before Refine lacks
  // them.
  if (initializer_) {
    if (std::optional<MonoInitialization> pair = initializer_->TakeWaitingPair()) {
      StartMapFrom(*pair, /*current_reported=*/true);
      WaitForWindowSolve();
    }
  }
  RefineWaitingFrames(/*all=*/true);  // The frames of the last window's keyframes.
  RefinementSummary out;
  if (options_.final_ba == "off") {
    out.report = "global BA off (ba.final_ba=off)";
    return out;
  }
  if (options_.final_ba == "after_loop" && num_loops_closed() == 0) {
    out.report = "global BA not run: no loop was closed (ba.final_ba=always runs it anyway)";
    return out;
  }
  const bool rig_offset = RigHasOffset();
  // Free when the online calibration found it, held when the user gave it.
  const bool offset_found = rig_offset && CalibratesRigOffset();
  if (options_.final_ba == "rig_offset" && !rig_offset) {
    out.report = rig_.is_stereo()
                     ? "global BA not run: the rig has no disparity offset, calibrated or given "
                       "(ba.final_ba=always runs it anyway)"
                     : "global BA not run: one camera has no disparity offset "
                       "(ba.final_ba=always runs it anyway)";
    return out;
  }
  if (keyframe_poses_.size() < 2) {
    out.report = "global BA: fewer than two keyframes, nothing to refine";
    return out;
  }
  GlobalBaProblem problem;
  problem.keyframes = keyframe_poses_;
  problem.held = gauge_keyframes_;
  for (const auto& [a, b] : unit_pairs_) {
    problem.fixed_distances.push_back(
        {a, b, (keyframe_poses_.at(b).translation() - keyframe_poses_.at(a).translation()).norm()});
  }
  problem.landmarks = map_points_;
  problem.observations = observation_archive_;
  // A rig whose offset was calibrated online: the global BA estimates it again with every
  // keyframe (those made before the calibration knew it were solved without it); a known offset
  // (ba.disparity_offset_px) is held. The offset is estimated in a solve of its own over the
  // tracks the window mapped (those its tests kept), then the trajectory is solved with every
  // track and the offset held. With every track in the offset's solve, the tracks the window
  // never mapped pull the offset with the start frame (KITTI 06 0-50 started at frames 0..9:
  // 0.16-0.22 px with them, 0.19-0.23 px without); without them in the trajectory's solve, the
  // global BA loses what it gains from them on rendered rigs (docs/backend.md, "Calibrating the
  // disparity offset online", item 6).
  StereoIntrinsics K = IntrinsicsOf(rig_, ba_.disparity_offset_px());
  GlobalBaOptions global_ba = options_.global_ba;
  global_ba.disparity_offset_prior_sigma_px = options_.ba.disparity_offset_prior_sigma_px;
  double offset_time_s = 0.0;
  if (offset_found) {
    GlobalBaProblem for_offset = problem;
    GlobalBaOptions offset_ba = global_ba;
    offset_ba.estimate_disparity_offset = true;
    offset_ba.triangulate_unmapped = false;
    const GlobalBaSummary so = SolveGlobalBa(K, offset_ba, &for_offset, stop_requested);
    offset_time_s = so.time_s;
    if (!so.usable) {
      out.report = so.BriefReport();
      out.time_s = so.time_s;
      out.stopped = so.stopped;
      if (!so.stopped) LOG(WARNING) << out.report << ": the run's estimates are kept";
      return out;
    }
    K.disparity_offset_px = so.disparity_offset_px;
  }
  global_ba.estimate_disparity_offset = false;
  const GlobalBaSummary s = SolveGlobalBa(K, global_ba, &problem, stop_requested);
  out.report = s.BriefReport();
  out.keyframes = s.num_keyframes;
  out.landmarks = s.num_landmarks;
  out.observations = s.num_observations;
  out.outliers_removed = s.num_outliers_removed;
  out.initial_cost = s.initial_cost;
  out.final_cost = s.final_cost;
  out.time_s = offset_time_s + s.time_s;
  out.stopped = s.stopped;
  if (!s.usable) {
    if (!s.stopped) LOG(WARNING) << out.report << ": the run's estimates are kept";
    return out;
  }
  out.done = true;
  if (offset_found) {
    online_offset_px_ = ba_.disparity_offset_px();
    ba_.set_disparity_offset_px(K.disparity_offset_px);
  }
  // Mono: each keyframe's change of local unit, from its distance to the next keyframe (the
  // previous one for the last); the frames stored relative to it are scaled by it.
  std::map<KeyframeId, double> unit_change;
  if (!rig_.is_stereo()) {
    for (auto it = keyframe_poses_.begin(); it != keyframe_poses_.end(); ++it) {
      auto other = std::next(it);
      if (other == keyframe_poses_.end()) other = std::prev(it);
      const double before = (other->second.translation() - it->second.translation()).norm();
      const double after = (problem.keyframes.at(other->first).translation() -
                            problem.keyframes.at(it->first).translation())
                               .norm();
      unit_change[it->first] = before > 1e-12 && after > 1e-12 ? after / before : 1.0;
    }
    for (FrameRecord& f : frames_) {
      const auto it = unit_change.find(f.reference);
      if (f.has_pose && it != unit_change.end()) f.T_kf_c.translation() *= it->second;
    }
  }
  keyframe_poses_ = problem.keyframes;
  // The refined landmarks, and the tracks the global BA mapped (their observation count: the
  // keyframes that saw them).
  std::map<LandmarkId, int> views;
  for (const auto& [kf, o] : problem.observations) ++views[o.landmark];
  for (const auto& [id, p_w] : problem.landmarks) {
    if (!map_points_.count(id)) landmark_observations_[id] = views[id];
    map_points_[id] = p_w;
  }
  for (const auto& [id, p_w] : map_points_) {
    if (ba_.LandmarkPosition(id)) ba_.SetLandmarkPosition(id, p_w);
  }
  ba_.ApplyCorrection(keyframe_poses_);
  if (!frames_.empty() && frames_.back().has_pose) {
    T_w_prev_ = KeyframePoseNow(frames_.back().reference) * frames_.back().T_kf_c;
  }
  return out;
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
