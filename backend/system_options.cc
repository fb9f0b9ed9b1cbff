#include "backend/system_options.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "core/config.h"
#include "core/error.h"

namespace dala {

bool SystemOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (estimator != "ba" && estimator != "ekf")
    return fail("estimator must be 'ba' or 'ekf', not '" + estimator + "'");
  if (mode != "stereo" && mode != "mono")
    return fail("mode must be 'stereo' or 'mono', not '" + mode + "'");
  if (mono_stereo_motion && !(mode == "mono" && estimator == "ekf"))
    return fail("mono_stereo_motion is an option of the mono EKF (estimator=ekf, mode=mono)");
  if (!(odometry_sigma_rot > 0) || !(odometry_sigma_trans >= 0) ||
      !(odometry_sigma_trans_fraction >= 0) ||
      !(odometry_sigma_trans > 0 || odometry_sigma_trans_fraction > 0))
    return fail("odometry_sigma_rot must be > 0, odometry_sigma_trans and "
                "odometry_sigma_trans_fraction >= 0 and not both 0");
  return frontend.IsValid(why) && ba.IsValid(why) && ekf_stereo.IsValid(why) &&
         ekf_mono.IsValid(why);
}

namespace {

// Visits every settable option as (section, key, pointer). One owner per section: "" (the
// System's), "harris", "matcher" (tracking), "stereo", "motion", "keyframe", "frontend",
// "loop" (place recognition), "ba" (the sliding-window estimator, its loop correction and its
// global BA), "mono_init" (the monocular BA's two-view initialisation), "ekf_stereo",
// "ekf_mono". Within a section the options users tune come first; those after
// BeginExperimental() are study options (docs/options.md, "Experimental"): settable like the
// others, left out of --dump_config unless set away from their default.
class OptionVisitor {
 public:
  virtual ~OptionVisitor() = default;
  virtual void Field(const std::string& section, const std::string& key, double* v) = 0;
  virtual void Field(const std::string& section, const std::string& key, int* v) = 0;
  virtual void Field(const std::string& section, const std::string& key, bool* v) = 0;
  virtual void Field(const std::string& section, const std::string& key, std::string* v) = 0;
  void BeginExperimental() { experimental_ = true; }
  void EndExperimental() { experimental_ = false; }

 protected:
  bool experimental() const { return experimental_; }

 private:
  bool experimental_ = false;
};

void VisitTopLevel(SystemOptions* o, OptionVisitor* v) {
  v->Field("", "estimator", &o->estimator);
  v->Field("", "mode", &o->mode);
  v->Field("", "mono_stereo_motion", &o->mono_stereo_motion);
  v->Field("", "use_odometry", &o->use_odometry);
  v->Field("", "odometry_sigma_rot", &o->odometry_sigma_rot);
  v->Field("", "odometry_sigma_trans", &o->odometry_sigma_trans);
  // Read as an int: a negative one is an error, not a wrapped uint64.
  int ransac_order_seed = static_cast<int>(o->ransac_order_seed);
  v->Field("", "ransac_order_seed", &ransac_order_seed);
  if (ransac_order_seed < 0) {
    throw Error() << "ransac_order_seed must be >= 0, not " << ransac_order_seed;
  }
  o->ransac_order_seed = static_cast<uint64_t>(ransac_order_seed);
  v->BeginExperimental();
  v->Field("", "odometry_sigma_trans_fraction", &o->odometry_sigma_trans_fraction);
  v->EndExperimental();
}

void VisitFrontend(FrontendOptions* f, OptionVisitor* v) {
  HarrisOptions& h = f->harris;
  v->Field("harris", "num_levels", &h.num_levels);
  v->Field("harris", "cell_size", &h.cell_size);
  v->Field("harris", "max_per_cell", &h.max_per_cell);
  v->Field("harris", "max_points", &h.max_points);
  v->BeginExperimental();
  v->Field("harris", "sigma_d", &h.sigma_d);
  v->Field("harris", "sigma_i", &h.sigma_i);
  v->Field("harris", "k", &h.k);
  v->EndExperimental();
  MatcherOptions& m = f->tracking_matcher;
  v->Field("matcher", "min_zncc", &m.min_zncc);
  v->BeginExperimental();
  v->Field("matcher", "min_support", &m.min_support);
  v->Field("matcher", "num_neighbours", &m.num_neighbours);
  v->Field("matcher", "propagate", &m.propagate);
  v->EndExperimental();
  StereoOptions& s = f->stereo;
  v->Field("stereo", "max_dv_px", &s.max_dv_px);
  v->Field("stereo", "min_depth_m", &s.min_depth_m);
  v->Field("stereo", "sigma_disparity", &s.sigma_disparity);
  v->Field("stereo", "min_zncc", &s.matcher.min_zncc);
  v->BeginExperimental();
  v->Field("stereo", "max_depth_m", &s.max_depth_m);
  v->Field("stereo", "max_depth_baselines", &s.max_depth_baselines);
  v->Field("stereo", "min_points_with_depth", &s.min_points_with_depth);
  v->Field("stereo", "refine_window", &s.refine_window);
  v->Field("stereo", "sigma_px", &s.sigma_px);
  v->EndExperimental();
  MotionEstimatorOptions& mo = f->motion;
  v->Field("motion", "ransac_threshold_px", &mo.ransac_threshold_px);
  v->Field("motion", "min_inliers", &mo.min_inliers);
  // The P3P RANSAC's seed, read as an int: a negative one is an error, not a wrapped uint64.
  int seed = static_cast<int>(mo.seed);
  v->Field("motion", "seed", &seed);
  if (seed < 0) throw Error() << "motion.seed must be >= 0, not " << seed;
  mo.seed = static_cast<uint64_t>(seed);
  v->BeginExperimental();
  v->Field("motion", "ransac_max_iterations", &mo.ransac_max_iterations);
  v->Field("motion", "sigma_px", &mo.sigma_px);
  v->EndExperimental();
  KeyframePolicyOptions& k = f->keyframe;
  v->Field("keyframe", "min_tracked_fraction", &k.min_tracked_fraction);
  v->Field("keyframe", "max_parallax_px", &k.max_parallax_px);
  v->Field("keyframe", "max_distance_baselines", &k.max_distance_baselines);
  v->Field("keyframe", "revisit_distance_baselines", &k.revisit_distance_baselines);
  v->Field("keyframe", "max_rotation_rad", &k.max_rotation_rad);
  v->Field("keyframe", "max_frames", &k.max_frames);
  v->BeginExperimental();
  v->Field("keyframe", "max_distance_m", &k.max_distance_m);
  v->Field("keyframe", "min_parallax_px", &k.min_parallax_px);
  v->Field("keyframe", "min_frames", &k.min_frames);
  v->Field("keyframe", "mono_parallax_without_rotation", &k.mono_parallax_without_rotation);
  v->EndExperimental();
  v->Field("frontend", "tracking_radius_px", &f->tracking_radius_px);
  v->Field("frontend", "local_map_search", &f->local_map.enable);
  v->Field("frontend", "local_map_search_stereo_when_tracked_below",
           &f->local_map.stereo_when_tracked_below);
  v->BeginExperimental();
  v->Field("frontend", "epipolar_gate_px", &f->epipolar_gate_px);
  v->Field("frontend", "keyframe_gate_px", &f->keyframe_gate_px);
  v->Field("frontend", "parallel_detection", &f->parallel_detection);
  v->Field("frontend", "local_map_radius_px", &f->local_map.radius_px);
  v->Field("frontend", "local_map_forget_after_frames", &f->local_map.forget_after_frames);
  v->Field("frontend", "mono_free_matching_below", &f->mono_free_matching_below);
  v->Field("frontend", "mono_init_rematch", &f->mono_init_rematch);
  v->EndExperimental();
  PlaceRecognitionOptions& l = f->loop;
  v->Field("loop", "enable", &l.enable);
  v->Field("loop", "min_frame_gap", &l.min_frame_gap);
  v->Field("loop", "min_appearance_score", &l.min_appearance_score);
  v->Field("loop", "min_inliers", &l.min_inliers);
  v->Field("loop", "gate_radius_m", &l.gate_radius_m);
  v->Field("loop", "relocalise", &l.relocalise);
  v->Field("loop", "relocalise_below_mapped", &l.relocalise_below_mapped);
  v->BeginExperimental();
  v->Field("loop", "top_k", &l.top_k);
  v->Field("loop", "max_shift_x", &l.max_shift_x);
  v->Field("loop", "max_shift_y", &l.max_shift_y);
  v->Field("loop", "spatial_gate", &l.spatial_gate);
  v->Field("loop", "gate_fraction", &l.gate_fraction);
  v->Field("loop", "gate_rotation_deg", &l.gate_rotation_deg);
  v->Field("loop", "gate_rotation_deg_per_m", &l.gate_rotation_deg_per_m);
  v->Field("loop", "mono_gate_fraction", &l.mono_gate_fraction);
  v->Field("loop", "min_inlier_ratio", &l.min_inlier_ratio);
  v->Field("loop", "keyframes_between_loops", &l.keyframes_between_loops);
  v->Field("loop", "pnp_ransac_threshold_px", &l.pnp.ransac_threshold_px);
  v->Field("loop", "pnp_ransac_max_iterations", &l.pnp.ransac_max_iterations);
  v->Field("loop", "one_entry_per_place", &l.one_entry_per_place);
  v->Field("loop", "place_min_inlier_fraction", &l.place_min_inlier_fraction);
  v->Field("loop", "place_prior_radius_px", &l.place_prior_radius_px);
  v->EndExperimental();
}

// SlidingWindowBa::LandmarkExit as a name, both ways from one table.
void VisitLandmarkExit(SlidingWindowBa::LandmarkExit* value, OptionVisitor* v) {
  using Exit = SlidingWindowBa::LandmarkExit;
  static const std::pair<const char*, Exit> kExitNames[] = {
      {"drop_tracked_observations", Exit::kDropTrackedObservations},
      {"drop_shared_observations", Exit::kDropSharedObservations},
      {"marginalize_all", Exit::kMarginalizeAll},
      {"marginalize_all_keep_tracks", Exit::kMarginalizeAllKeepTracks}};
  std::string exit;
  for (const auto& [name, known] : kExitNames) {
    if (known == *value) exit = name;
  }
  v->Field("ba", "landmark_exit", &exit);
  const auto* known = std::find_if(std::begin(kExitNames), std::end(kExitNames),
                                   [&](const auto& entry) { return exit == entry.first; });
  if (known == std::end(kExitNames)) {
    std::string names;
    for (const auto& entry : kExitNames) {
      names += std::string(names.empty() ? "" : ", ") + entry.first;
    }
    throw Error() << "ba.landmark_exit '" << exit << "' is unknown: use one of " << names;
  }
  *value = known->second;
}

void VisitBa(SlidingWindowEstimatorOptions* b, OptionVisitor* v) {
  v->Field("ba", "window_size", &b->ba.window_size);
  v->Field("ba", "max_num_iterations", &b->ba.max_num_iterations);
  // The window solver's wall-clock limit: 0 = none (the default: results do not depend on the
  // machine's load); a positive value is a non-deterministic opt-in (backend/ba/solver_time.h).
  v->Field("ba", "max_solver_time_in_seconds", &b->ba.max_solver_time_in_seconds);
  v->Field("ba", "loss_scale", &b->ba.loss_scale);
  v->Field("ba", "sigma_px", &b->observation_sigma_px);
  v->Field("ba", "tracking_sigma_px", &b->tracking_sigma_px);
  v->Field("ba", "min_triangulation_parallax_deg", &b->ba.min_triangulation_parallax_deg);
  v->Field("ba", "max_new_landmarks_per_keyframe", &b->max_new_landmarks_per_keyframe);
  v->Field("ba", "background_solve", &b->background_solve);
  v->Field("ba", "final_ba", &b->final_ba);
  v->Field("ba", "calibrate_disparity_offset", &b->ba.calibrate_disparity_offset);
  v->Field("ba", "disparity_offset_px", &b->ba.disparity_offset_px);
  v->Field("ba", "mono_reinit_after_lost_frames", &b->mono_reinit_after_lost_frames);
  v->Field("ba", "loop_correct", &b->loop.enable);
  v->BeginExperimental();
  v->Field("ba", "use_marginalization", &b->ba.use_marginalization);
  v->Field("ba", "num_fixed_keyframes", &b->ba.num_fixed_keyframes);
  v->Field("ba", "num_held_keyframes", &b->ba.num_held_keyframes);
  v->Field("ba", "cull_held_keyframes", &b->cull_held_keyframes);
  v->Field("ba", "refine_frames", &b->refine_frames);
  v->Field("ba", "mono_bridge", &b->mono_bridge);
  // Landmark fusion (SlidingWindowBa::FuseLandmarks), off: docs/monocular.md "Landmark fusion".
  v->Field("ba", "fuse_radius_px", &b->ba.fuse_radius_px);
  v->Field("ba", "final_ba_max_iterations", &b->global_ba.max_num_iterations);
  VisitLandmarkExit(&b->ba.landmark_exit, v);
  v->Field("ba", "pose_only_max_solver_time_in_seconds", &b->pose_only.max_solver_time_in_seconds);
  v->Field("ba", "pose_graph_max_solver_time_in_seconds",
           &b->loop.pose_graph.max_solver_time_in_seconds);
  v->Field("ba", "remove_outliers", &b->ba.remove_outliers);
  v->Field("ba", "min_observations", &b->ba.min_observations);
  v->Field("ba", "estimate_disparity_offset", &b->ba.estimate_disparity_offset);
  v->Field("ba", "disparity_offset_prior_sigma_px", &b->ba.disparity_offset_prior_sigma_px);
  // The calibration's tests (backend/ba/disparity_offset_calibration.h).
  DisparityOffsetCalibration::Options& oc = b->ba.offset_calibration;
  v->Field("ba", "offset_calibration_min_estimates", &oc.min_estimates);
  v->Field("ba", "offset_calibration_bias_px", &oc.bias_px);
  v->Field("ba", "offset_calibration_converged_after_estimates", &oc.converged_after_estimates);
  v->Field("ba", "offset_calibration_stable_px", &oc.stable_px);
  v->Field("ba", "offset_calibration_min_window_span_baselines", &oc.min_window_span_baselines);
  v->Field("ba", "offset_calibration_max_prior_offset_change_px", &oc.max_prior_offset_change_px);
  // The loop correction's pose graph (backend/sliding_window_loop_closure.h).
  BaLoopClosureOptions& bl = b->loop;
  v->Field("ba", "loop_rot_sigma0", &bl.rot_sigma0);
  v->Field("ba", "loop_rot_sigma_per_m", &bl.rot_sigma_per_m);
  v->Field("ba", "loop_trans_sigma0", &bl.trans_sigma0);
  v->Field("ba", "loop_trans_sigma_per_m", &bl.trans_sigma_per_m);
  v->Field("ba", "loop_min_sigma_rot", &bl.loop_min_sigma_rot);
  v->Field("ba", "loop_min_sigma_trans", &bl.loop_min_sigma_trans);
  v->Field("ba", "loop_mono_scale_sigma", &bl.mono_scale_sigma);
  v->Field("ba", "loop_mono_loop_scale_sigma", &bl.mono_loop_scale_sigma);
  v->Field("ba", "loop_sim3_relative_tolerance", &bl.sim3.relative_tolerance);
  v->Field("ba", "loop_sim3_min_inliers", &bl.sim3.min_inliers);
  v->EndExperimental();
  MonoInitializerOptions& mi = b->mono_init;
  v->Field("mono_init", "min_parallax_deg", &mi.two_view.min_parallax_deg);
  v->Field("mono_init", "min_points", &mi.two_view.min_points);
  v->Field("mono_init", "min_reference_features", &mi.min_reference_features);
  v->Field("mono_init", "max_pending_frames", &mi.max_pending_frames);
  v->BeginExperimental();
  v->Field("mono_init", "next_frame_min_inlier_ratio", &mi.next_frame_min_inlier_ratio);
  v->Field("mono_init", "min_point_parallax_deg", &mi.two_view.min_point_parallax_deg);
  v->Field("mono_init", "min_residual_parallax_deg", &mi.two_view.min_residual_parallax_deg);
  v->Field("mono_init", "min_cells", &mi.two_view.min_cells);
  v->Field("mono_init", "homography_ratio", &mi.two_view.homography_ratio);
  v->Field("mono_init", "sigma_px", &mi.two_view.sigma_px);
  v->Field("mono_init", "refine", &mi.refine);
  v->EndExperimental();
}

void VisitEkf(StereoEkfOptions* es, MonoEkfOptions* em, OptionVisitor* v) {
  v->Field("ekf_stereo", "max_landmarks", &es->max_landmarks);
  v->Field("ekf_stereo", "gate_chi2", &es->gate_chi2);
  v->Field("ekf_stereo", "motion_covariance_scale", &es->motion_covariance_scale);
  v->BeginExperimental();
  v->Field("ekf_stereo", "grid_cols", &es->grid_cols);
  v->Field("ekf_stereo", "grid_rows", &es->grid_rows);
  v->Field("ekf_stereo", "target_per_zone", &es->target_per_zone);
  v->Field("ekf_stereo", "new_per_zone_per_frame", &es->new_per_zone_per_frame);
  v->Field("ekf_stereo", "max_relative_depth_sigma", &es->max_relative_depth_sigma);
  v->Field("ekf_stereo", "loop_min_gap_frames", &es->loop_min_gap_frames);
  v->Field("ekf_stereo", "loop_gate_chi2", &es->loop_gate_chi2);
  v->EndExperimental();
  v->Field("ekf_mono", "max_landmarks", &em->max_landmarks);
  v->Field("ekf_mono", "d_min", &em->d_min);
  v->Field("ekf_mono", "d_max", &em->d_max);
  v->Field("ekf_mono", "alpha", &em->alpha);
  v->Field("ekf_mono", "gate_chi2", &em->gate_chi2);
  v->Field("ekf_mono", "prediction", &em->prediction);
  v->BeginExperimental();
  v->Field("ekf_mono", "k_sigma", &em->k_sigma);
  v->Field("ekf_mono", "prune_chi2", &em->prune_chi2);
  v->Field("ekf_mono", "sprt_false_alarm", &em->sprt_false_alarm);
  v->Field("ekf_mono", "sprt_missed_detection", &em->sprt_missed_detection);
  v->Field("ekf_mono", "min_image_motion_chi2", &em->min_image_motion_chi2);
  v->Field("ekf_mono", "cv_angular_acceleration_sigma", &em->cv_angular_acceleration_sigma);
  v->Field("ekf_mono", "cv_linear_acceleration_sigma", &em->cv_linear_acceleration_sigma);
  v->Field("ekf_mono", "init_rotation_sigma", &em->init_rotation_sigma);
  v->Field("ekf_mono", "init_translation_sigma", &em->init_translation_sigma);
  v->Field("ekf_mono", "init_per_zone", &em->init_per_zone);
  v->EndExperimental();
}

void VisitOptions(SystemOptions* o, OptionVisitor* v) {
  VisitTopLevel(o, v);
  VisitFrontend(&o->frontend, v);
  VisitBa(&o->ba, v);
  VisitEkf(&o->ekf_stereo, &o->ekf_mono, v);
}

// Reads every field from the YAML sections, then rejects keys nobody asked for.
class YamlReader : public OptionVisitor {
 public:
  explicit YamlReader(const ConfigNode& root) : root_(root) {}
  void Field(const std::string& s, const std::string& k, double* v) override { Node(s).Read(k.c_str(), v); }
  void Field(const std::string& s, const std::string& k, int* v) override { Node(s).Read(k.c_str(), v); }
  void Field(const std::string& s, const std::string& k, bool* v) override { Node(s).Read(k.c_str(), v); }
  void Field(const std::string& s, const std::string& k, std::string* v) override {
    Node(s).Read(k.c_str(), v);
  }
  void Check() {
    for (auto& [name, node] : children_) node.CheckNoUnknownKeys();
    root_.CheckNoUnknownKeys();
  }

 private:
  const ConfigNode& Node(const std::string& section) {
    if (section.empty()) return root_;
    auto it = children_.find(section);
    if (it == children_.end()) it = children_.emplace(section, root_.Child(section.c_str())).first;
    return it->second;
  }
  const ConfigNode& root_;
  std::map<std::string, ConfigNode> children_;
};

std::string Qualified(const std::string& section, const std::string& key) {
  return section.empty() ? key : section + "." + key;
}

// Keys that existed and were removed: a file or --set that still uses one gets an error that
// says what replaced it, not only "unknown key".
const std::map<std::string, std::string>& RemovedKeys() {
  static const std::map<std::string, std::string> removed = {
      {"frontend.local_map_search_stereo",
       "removed: frontend.local_map_search_stereo_when_tracked_below=1 runs the stereo search "
       "from the first tracked frame on"},
      {"frontend.match_keyframe",
       "removed: lost landmarks are always re-acquired from the last keyframe"},
      {"stereo.refine_disparity", "removed: the right abscissa is always refined to sub-pixel"},
      {"ba.final_ba_all_tracks", "removed: the global BA always solves every track"},
      {"ba.max_landmark_depth_m",
       "removed: a depth limit biases the far points kept (stereo.max_depth_baselines limits "
       "the frontend's depths)"},
      {"loop.ba_correct", "renamed to ba.loop_correct (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_rot_sigma0", "renamed to ba.loop_rot_sigma0 (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_rot_sigma_per_m", "renamed to ba.loop_rot_sigma_per_m (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_trans_sigma0", "renamed to ba.loop_trans_sigma0 (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_trans_sigma_per_m", "renamed to ba.loop_trans_sigma_per_m (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_loop_min_sigma_rot", "renamed to ba.loop_min_sigma_rot (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_loop_min_sigma_trans", "renamed to ba.loop_min_sigma_trans (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_mono_scale_sigma", "renamed to ba.loop_mono_scale_sigma (loop.* is place recognition, ba.* the estimator)"},
      {"loop.ba_mono_loop_scale_sigma", "renamed to ba.loop_mono_loop_scale_sigma (loop.* is place recognition, ba.* the estimator)"},
      {"loop.mono_sim3_relative_tolerance", "renamed to ba.loop_sim3_relative_tolerance (loop.* is place recognition, ba.* the estimator)"},
      {"loop.mono_sim3_min_inliers", "renamed to ba.loop_sim3_min_inliers (loop.* is place recognition, ba.* the estimator)"},
      {"ba.offset_calibration_min_offset_px",
       "replaced by ba.offset_calibration_bias_px (the offset is weighted from 0 at the bias to "
       "1 at twice it, not gated; backend/ba/disparity_offset_calibration.h)"},
      {"ba.offset_calibration_min_mean_over_sd",
       "removed: the calibration uses the median of the window estimates, which a few wild "
       "windows do not move, instead of a test against their standard deviation"},
  };
  return removed;
}

[[noreturn]] void ThrowRemovedKey(const std::string& where, const std::string& key) {
  throw Error() << where << key << ": this option no longer exists; " << RemovedKeys().at(key);
}

// Throws for the first removed key a YAML file sets.
void RejectRemovedKeys(const ConfigNode& root, const std::string& path) {
  for (const auto& [key, note] : RemovedKeys()) {
    const size_t dot = key.find('.');
    const std::string section = key.substr(0, dot), name = key.substr(dot + 1);
    if (root.Has(section.c_str()) && root.Child(section.c_str()).Has(name.c_str())) {
      ThrowRemovedKey(path + ": ", key);
    }
  }
}

// Applies one "section.key=value".
class Setter : public OptionVisitor {
 public:
  Setter(std::string key, std::string value) : key_(std::move(key)), value_(std::move(value)) {}
  void Field(const std::string& s, const std::string& k, double* v) override {
    if (!Match(s, k)) return;
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(value_.c_str(), &end);
    if (value_.empty() || *end != '\0' || errno) Bad("a number");
    *v = x;
  }
  void Field(const std::string& s, const std::string& k, int* v) override {
    if (!Match(s, k)) return;
    char* end = nullptr;
    errno = 0;
    const long long x = std::strtoll(value_.c_str(), &end, 10);
    if (value_.empty() || *end != '\0' || errno) Bad("an integer");
    if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) {
      Bad("an integer from -2147483648 to 2147483647");
    }
    *v = static_cast<int>(x);
  }
  void Field(const std::string& s, const std::string& k, bool* v) override {
    if (!Match(s, k)) return;
    if (value_ == "true" || value_ == "1") {
      *v = true;
    } else if (value_ == "false" || value_ == "0") {
      *v = false;
    } else {
      Bad("true or false");
    }
  }
  void Field(const std::string& s, const std::string& k, std::string* v) override {
    if (Match(s, k)) *v = value_;
  }
  bool found() const { return found_; }
  const std::string& known() const { return known_; }

 private:
  bool Match(const std::string& s, const std::string& k) {
    known_ += (known_.empty() ? "" : ", ") + Qualified(s, k);
    if (Qualified(s, k) != key_) return false;
    found_ = true;
    return true;
  }
  [[noreturn]] void Bad(const char* what) {
    throw Error() << "--set " << key_ << "=" << value_ << ": the value must be " << what;
  }
  std::string key_, value_;
  bool found_ = false;
  std::string known_;
};

// Writes the options as YAML sections. With `defaults`, an experimental option is written only
// when its value differs from the default there (so that a dump loads back to the same options).
class YamlWriter : public OptionVisitor {
 public:
  explicit YamlWriter(const nlohmann::json* defaults) : defaults_(defaults) {}
  void Field(const std::string& s, const std::string& k, double* v) override {
    if (Shown(s, k, *v)) Put(s, k, Num(*v));
  }
  void Field(const std::string& s, const std::string& k, int* v) override {
    if (Shown(s, k, *v)) Put(s, k, std::to_string(*v));
  }
  void Field(const std::string& s, const std::string& k, bool* v) override {
    if (Shown(s, k, *v)) Put(s, k, *v ? "1" : "0");
  }
  void Field(const std::string& s, const std::string& k, std::string* v) override {
    if (Shown(s, k, *v)) Put(s, k, "\"" + *v + "\"");
  }
  std::string Text() const { return os_.str(); }

 private:
  template <typename T>
  bool Shown(const std::string& s, const std::string& k, const T& value) const {
    if (!experimental() || defaults_ == nullptr) return true;
    const nlohmann::json& section = s.empty() ? *defaults_ : defaults_->at(s);
    return section.at(k) != nlohmann::json(value);
  }
  static std::string Num(double v) {
    std::ostringstream os;
    os.precision(17);
    os << v;
    std::string s = os.str();
    // YAML (cv::FileStorage) reads "2" as an int: keep doubles recognisable.
    if (s.find_first_of(".eE") == std::string::npos && s.find("inf") == std::string::npos) s += ".0";
    return s;
  }
  void Put(const std::string& s, const std::string& k, const std::string& value) {
    if (s != section_) {
      section_ = s;
      os_ << s << ":\n";
    }
    os_ << (s.empty() ? "" : "  ") << k << ": " << value << "\n";
  }
  const nlohmann::json* defaults_;
  std::ostringstream os_;
  std::string section_;
};

class JsonWriter : public OptionVisitor {
 public:
  void Field(const std::string& s, const std::string& k, double* v) override { At(s)[k] = *v; }
  void Field(const std::string& s, const std::string& k, int* v) override { At(s)[k] = *v; }
  void Field(const std::string& s, const std::string& k, bool* v) override { At(s)[k] = *v; }
  void Field(const std::string& s, const std::string& k, std::string* v) override { At(s)[k] = *v; }
  nlohmann::json json = nlohmann::json::object();

 private:
  nlohmann::json& At(const std::string& s) { return s.empty() ? json : json[s]; }
};

// Lists the keys, the experimental ones only when asked.
class KeyLister : public OptionVisitor {
 public:
  explicit KeyLister(bool all) : all_(all) {}
  void Field(const std::string& s, const std::string& k, double*) override { Add(s, k); }
  void Field(const std::string& s, const std::string& k, int*) override { Add(s, k); }
  void Field(const std::string& s, const std::string& k, bool*) override { Add(s, k); }
  void Field(const std::string& s, const std::string& k, std::string*) override { Add(s, k); }
  std::vector<std::string> keys;

 private:
  void Add(const std::string& s, const std::string& k) {
    if (all_ || !experimental()) keys.push_back(Qualified(s, k));
  }
  bool all_;
};

}  // namespace

void LoadSystemOptions(const std::string& yaml_path, SystemOptions* options) {
  const ConfigNode root = LoadConfigFile(yaml_path);
  RejectRemovedKeys(root, yaml_path);
  YamlReader reader(root);
  VisitOptions(options, &reader);
  reader.Check();
  std::string why;
  if (!options->IsValid(&why)) throw Error() << yaml_path << ": invalid options: " << why;
}

void SetSystemOption(const std::string& assignment, SystemOptions* options) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw Error() << "--set '" << assignment << "': expected section.key=value, e.g. ba.window_size=10";
  }
  Setter setter(assignment.substr(0, eq), assignment.substr(eq + 1));
  VisitOptions(options, &setter);
  if (!setter.found()) {
    const std::string key = assignment.substr(0, eq);
    if (RemovedKeys().count(key)) ThrowRemovedKey("--set ", key);
    throw Error() << "--set: unknown option '" << assignment.substr(0, eq)
                  << "'; known options: " << setter.known();
  }
  std::string why;
  if (!options->IsValid(&why)) throw Error() << "--set " << assignment << ": " << why;
}

std::string SystemOptionsToYaml(const SystemOptions& options, OptionSet which) {
  SystemOptions copy = options;
  const nlohmann::json defaults = SystemOptionsToJson(SystemOptions());
  YamlWriter writer(which == OptionSet::kAll ? nullptr : &defaults);
  VisitOptions(&copy, &writer);
  const char* what = which == OptionSet::kAll
                         ? "# Every option, the experimental ones too (docs/options.md).\n"
                         : "# The options users tune (docs/options.md), and any experimental one set away\n"
                           "# from its default; --dump_config_all lists every option.\n";
  return std::string("%YAML:1.0\n---\n") + what + writer.Text();
}

nlohmann::json SystemOptionsToJson(const SystemOptions& options) {
  SystemOptions copy = options;
  JsonWriter writer;
  VisitOptions(&copy, &writer);
  return writer.json;
}

std::vector<std::string> SystemOptionKeys(OptionSet which) {
  SystemOptions options;
  KeyLister lister(which == OptionSet::kAll);
  VisitOptions(&options, &lister);
  return lister.keys;
}

}  // namespace dala
