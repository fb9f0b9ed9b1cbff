#ifndef DALA_BACKEND_SYSTEM_OPTIONS_H_
#define DALA_BACKEND_SYSTEM_OPTIONS_H_

// SystemOptions: every component's options in one struct (DESIGN.md "Configuration"), and ONE
// table of their settable keys (system_options.cc), used four ways: the YAML loader (`dala run
// --config`), `--set section.key=value`, `--dump_config`, and the "options" of the JSON run
// report (every key). docs/options.md says when to change each; the experimental ones (study
// options) are settable too but left out of --dump_config.
//
//   estimator: ba            # ba | ekf
//   mode: stereo             # stereo | mono
//   harris: {num_levels: 2, max_points: 1000, ...}
//   ba: {window_size: 8, ...}

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "backend/ekf/mono_ekf.h"
#include "backend/ekf/stereo_ekf.h"
#include "backend/sliding_window_estimator.h"
#include "frontend/frontend.h"

namespace dala {

struct SystemOptions {
  std::string estimator = "ba";  // "ba" (sliding-window BA) or "ekf" (the paper's filters).
  std::string mode = "stereo";   // "stereo" or "mono".
  // Mode "mono" means one camera: on a stereo dataset only the left images are read (the same
  // run as on a left-only copy). true: the paper's setting instead (the mono EKF only): the
  // frontend runs on the stereo pair and its visual motion is the filter's dead reckoning,
  // which fixes the scale, while the filter observes left pixels only.
  bool mono_stereo_motion = false;
  // A dataset's odometry (Frame::T_w_odom, e.g. the odometry.txt of `dala synth --odometry`):
  // System::Track gives each frame's FrameMeasurement::odometry T_prev_cur =
  // T_w_odom_prev^-1 T_w_odom_cur with the covariance of the right perturbation
  // diag(sr^2 I3, st^2 I3), sr = odometry_sigma_rot (rad per frame), st = odometry_sigma_trans +
  // odometry_sigma_trans_fraction |t_prev_cur| (m); the defaults are those `dala synth` draws its
  // noise with (core/sim/synthetic_sequence.h). The mono EKF uses it (the scale then is metric);
  // the other estimators ignore it. false: not given.
  bool use_odometry = true;
  double odometry_sigma_rot = 0.002;
  double odometry_sigma_trans = 0.005;
  double odometry_sigma_trans_fraction = 0.02;
  // The draws of every OpenCV RANSAC of the run (the tracking matcher's fundamental matrix, one
  // camera's essential matrix, homography, two-view initialisation and PnP recovery): OpenCV seeds
  // its own generator on every call, so its draws are set by the order of the correspondences
  // (core/ransac_order.h). 0: as given (OpenCV's own draws); N > 0: shuffled with seed N. System
  // copies it into those estimators' options. With motion.seed (the stereo motion's P3P
  // RANSAC) it is how to check that a result does not depend on the draws.
  uint64_t ransac_order_seed = 0;
  FrontendOptions frontend;
  SlidingWindowEstimatorOptions ba;
  StereoEkfOptions ekf_stereo;
  MonoEkfOptions ekf_mono;

  bool IsValid(std::string* why) const;
};

// Loads a YAML file over `options` (keys absent keep their value). dala::Error on an unknown key,
// a wrong type or an unreadable file, naming the file and the key.
void LoadSystemOptions(const std::string& yaml_path, SystemOptions* options);
// Applies "section.key=value" (or "key=value" for top-level keys). dala::Error naming the key
// and the known keys of that section when it does not exist, or the value when it does not parse.
void SetSystemOption(const std::string& assignment, SystemOptions* options);
// The options as YAML (what --dump_config prints; LoadSystemOptions reads it back to the same
// options). kUser: the options users tune (docs/options.md) and the experimental ones whose value
// differs from the default; kAll: every option.
enum class OptionSet { kUser, kAll };
std::string SystemOptionsToYaml(const SystemOptions& options, OptionSet which = OptionSet::kUser);
// The keys ("section.key", or "key" at the top level) in table order: kUser the options users
// tune, kAll every option.
std::vector<std::string> SystemOptionKeys(OptionSet which);
nlohmann::json SystemOptionsToJson(const SystemOptions& options);

}  // namespace dala

#endif  // DALA_BACKEND_SYSTEM_OPTIONS_H_
