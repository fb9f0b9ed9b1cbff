#ifndef DALA_CORE_EVAL_EVALUATE_H_
#define DALA_CORE_EVAL_EVALUATE_H_

// Trajectory evaluation in one call: association, alignment, ATE, RPE and the KITTI segment
// errors, with the conventions of evo (evo_ape / evo_rpe) and the KITTI odometry devkit. The
// `dala eval`, `dala run` (report.json) and `dala bench` commands all go through Evaluate() and
// EvalResultToJson(), so every metric is defined here once. docs/evaluation.md gives the formulas.
//
//   dala::EvalOptions options;
//   options.alignment = dala::AlignmentType::kSim3;  // monocular
//   const dala::EvalResult r = dala::Evaluate(gt, est, options);
//   if (!r.ok) LOG(ERROR) << r.error;
//   else std::cout << EvalResultToJson(r).dump(2);

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/eval/alignment.h"
#include "core/eval/association.h"
#include "core/eval/ate.h"
#include "core/eval/kitti_segments.h"
#include "core/eval/rpe.h"
#include "core/trajectory.h"

namespace dala {

struct EvalOptions {
  // Alignment of the estimate onto the ground truth before the ATE (Umeyama on the positions of
  // the associated pairs). Sim(3) for monocular estimates whose scale is free.
  AlignmentType alignment = AlignmentType::kSE3;
  // Maximum |t_gt - t_est| for two poses to be associated, seconds (evo and TUM default 0.01).
  double max_time_diff_s = 0.01;
  // RPE step and its unit (evo_rpe defaults: 1 frame).
  double rpe_delta = 1.0;
  DeltaUnit rpe_delta_unit = DeltaUnit::kFrames;
  // KITTI devkit segment errors (computed when the path allows at least one segment).
  bool kitti_segments = true;
  KittiSegmentOptions kitti;

  bool IsValid(std::string* why) const;
};

struct EvalResult {
  bool ok = false;    // False when no answer exists (no pairs, lengths differ, ...): see error.
  std::string error;  // Why, naming sizes, time ranges and the option to change.

  EvalOptions options;
  PairedPoses pairs;                    // Associated poses (estimate not aligned).
  Sim3Alignment alignment;              // Estimate world -> ground truth world (identity for none).
  std::vector<double> pair_distance_m;  // Ground truth path length up to each pair (plots).
  double gt_path_length_m = 0.0;        // Along the paired ground truth poses.
  double est_path_length_m = 0.0;       // Along the paired, aligned (scaled) estimate.
  AteResult ate;
  bool has_rpe = false;
  RpeResult rpe;
  bool has_kitti = false;
  KittiSegmentResult kitti;
  // Caveats on reading the numbers (not errors), e.g. an aligned ATE rotation on a straight
  // path (see Evaluate).
  std::vector<std::string> warnings;
};

// Evaluates `est` against `gt`. Never throws on data: a result with ok == false says why.
// Warning: with an SE(3) / Sim(3) alignment, a rotation about the ground truth's principal axis
// moves the positions by (angle x their distance from that axis). When that distance (RMS) is
// small against the ATE, positions cannot fix this rotation (a straight drive: KITTI 06 0-50,
// 5 cm of lateral spread over 60 m), so the ATE rotation errors (rot_*_deg) then mostly measure
// the arbitrary fitted roll. A warning says so when atan(ATE rmse / lateral spread) > 5 deg.
// Options must be valid (CHECKed: validate user input with IsValid first).
EvalResult Evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options);

// The result as JSON:
//   {"pairs", "path_length", "alignment", "scale", "max_time_diff",
//    "ate": {"rmse", "mean", "median", "std", "min", "max", "rot_rmse_deg", "rot_mean_deg",
//            "rot_max_deg"},
//    "rpe": {"delta", "unit", "pairs", "trans_rmse", "trans_mean", "trans_median", "trans_max",
//            "rot_rmse_deg", "rot_mean_deg", "rot_median_deg", "rot_max_deg"},   (when defined)
//    "kitti": {"t_err_percent", "r_err_deg_per_100m", "segments", "per_length": [...]}}
//                                                                              (when long enough)
// A failed result gives {"ok": false, "error": "..."}.
nlohmann::json EvalResultToJson(const EvalResult& result);

// A readable multi-line table of the result (what `dala eval` prints).
std::string EvalResultToTable(const EvalResult& result);

}  // namespace dala

#endif  // DALA_CORE_EVAL_EVALUATE_H_
