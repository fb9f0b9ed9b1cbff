#ifndef DALA_TOOLS_BENCH_RUN_RESULT_H_
#define DALA_TOOLS_BENCH_RUN_RESULT_H_

// What `dala bench` records of one run (one row of results.json / .csv / .md). Metrics that do
// not exist for a run (no ground truth, a failed run, a path too short for KITTI segments) are
// empty optionals, written as JSON null and as empty CSV cells.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace dala::bench {

// ok: the run finished and was evaluated; failed: non-zero exit (or no output); crashed: killed
// by a signal; timeout: killed after the suite's timeout_s; unsupported: `dala run` rejected
// the estimator/mode combination (exit 2 saying "not supported"/"unsupported").
inline constexpr const char* kStatusOk = "ok";
inline constexpr const char* kStatusFailed = "failed";
inline constexpr const char* kStatusCrashed = "crashed";
inline constexpr const char* kStatusTimeout = "timeout";
inline constexpr const char* kStatusUnsupported = "unsupported";

struct BenchRunResult {
  int index = 0;         // In the full sorted run list.
  std::string sequence;  // Sequence name.
  std::string config;    // Configuration name.
  // The sequence's variant: "seed2", "start3", or empty for a sequence run once (suite.h).
  std::string variant;
  std::optional<int> start;  // `dala run --first_frame` of a dataset run (0 without starts).
  std::optional<int> seed;   // The rendering seed of a rendered preset.
  std::string estimator;     // "ba" | "ekf".
  std::string mode;          // "stereo" | "mono".
  std::string status;        // See above.
  std::string error;         // Why a run is not ok, or why a metric is missing; empty otherwise.
  std::string command;       // The `dala run` command line.
  std::string run_dir;       // Relative to the bench output folder: runs/SEQ[@VARIANT]/CONFIG.
  std::optional<int> exit_code;
  std::optional<int> signal;
  double wall_s = 0.0;
  double peak_rss_mb = 0.0;

  // From report.json.
  std::optional<int> frames;
  std::optional<double> fps;
  std::optional<double> ms_median, ms_p95, ms_max;  // Per-frame "total" time.
  std::optional<int> landmarks, keyframes, tracking_failures;
  // Keyframes left in the map after culling (absent: the estimator keeps none, the EKFs).
  std::optional<int> keyframes_in_map;
  // The stereo rig's disparity offset at the end of the run, px (absent: the estimator has
  // none; the BA calibrates it, docs/backend.md).
  std::optional<double> disparity_offset_px;

  // Re-evaluated by the harness (core/eval Evaluate), see docs/benchmarking.md.
  std::string alignment;  // "se3" (stereo) | "sim3" (mono).
  std::optional<int> pairs;
  std::optional<double> path_length_m;
  std::optional<double> ate_rmse, ate_mean, ate_median, ate_max;
  std::optional<double> scale;
  std::optional<double> rpe_trans, rpe_rot_deg;             // RPE over 1 frame: RMSE, m and deg.
  std::optional<double> rpe10_trans, rpe10_rot_deg;         // RPE over 10 frames.
  std::optional<double> t_err_percent, r_err_deg_per_100m;  // KITTI segments.

  // Plots, relative to the bench output folder; empty when not drawn.
  std::string plot_trajectory;  // PlotEvaluation: top view over ground truth + ATE along path.
  std::string plot_timing;      // Per-frame time.
};

// SEQ or SEQ@VARIANT, then /CONFIG: the run's identity within a bench (and its folder under runs/).
std::string RunKey(const BenchRunResult& r);

nlohmann::json ToJson(const BenchRunResult& r);
// Throws dala::Error naming `where` on a missing or mistyped key.
BenchRunResult BenchRunResultFromJson(const nlohmann::json& j, const std::string& where);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_RUN_RESULT_H_
