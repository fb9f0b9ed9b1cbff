#include "core/eval/evaluate.h"

#include <glog/logging.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace dala {

bool EvalOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(max_time_diff_s >= 0.0) || !std::isfinite(max_time_diff_s)) {
    return fail("max_time_diff_s must be a finite number >= 0");
  }
  if (!(rpe_delta > 0.0) || !std::isfinite(rpe_delta)) {
    return fail("rpe_delta must be a finite number > 0");
  }
  if (rpe_delta_unit == DeltaUnit::kFrames && rpe_delta != std::floor(rpe_delta)) {
    return fail("rpe_delta must be an integer number of frames when the unit is frames");
  }
  if (kitti.step_frames < 1) return fail("kitti.step_frames must be >= 1");
  for (double l : kitti.lengths_m) {
    if (!(l > 0.0)) return fail("kitti.lengths_m must all be > 0");
  }
  return true;
}

namespace {

// The warning of evaluate.h on the rotation about the path, or "" (positions p_gt, n >= 3).
std::string PathAxisRotationWarning(const std::vector<Eigen::Vector3d>& p_gt, double ate_rmse) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : p_gt) mean += p;
  mean /= static_cast<double>(p_gt.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : p_gt) cov += (p - mean) * (p - mean).transpose();
  cov /= static_cast<double>(p_gt.size());
  const Eigen::Vector3d lambda = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
  // RMS distance from the principal axis: the two smaller eigenvalues (ascending order).
  const double lateral_m = std::sqrt(std::max(0.0, lambda[0] + lambda[1]));
  constexpr double kMaxAmbiguityDeg = 5.0;
  const double ambiguity_deg = std::atan2(ate_rmse, lateral_m) * 180.0 / M_PI;
  if (!(ambiguity_deg > kMaxAmbiguityDeg)) return "";
  char buf[400];
  std::snprintf(buf, sizeof(buf),
                "the ground-truth positions lie almost on a line or at one point (%.3f m RMS off "
                "their axis against an ATE of %.3f m): the alignment cannot fix the rotation about "
                "that axis (to within ~%.0f deg), so the ATE rotation errors are not meaningful; "
                "the translation errors and RPE are",
                lateral_m, ate_rmse, ambiguity_deg);
  return buf;
}

}  // namespace

EvalResult Evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options) {
  std::string why;
  CHECK(options.IsValid(&why)) << "invalid EvalOptions: " << why;
  EvalResult r;
  r.options = options;
  if (!PairTrajectories(gt, est, options.max_time_diff_s, &r.pairs, &why)) {
    r.error = why;
    return r;
  }
  const size_t n = r.pairs.size();
  std::vector<Eigen::Vector3d> p_gt(n);
  std::vector<Eigen::Vector3d> p_est(n);
  for (size_t i = 0; i < n; ++i) {
    p_gt[i] = r.pairs.T_w_c_gt[i].translation();
    p_est[i] = r.pairs.T_w_c_est[i].translation();
  }
  if (!ComputeAlignment(p_est, p_gt, options.alignment, &r.alignment, &why)) {
    r.error = why;
    return r;
  }
  std::vector<Pose> T_w_c_aligned(n);
  for (size_t i = 0; i < n; ++i) T_w_c_aligned[i] = r.alignment.Apply(r.pairs.T_w_c_est[i]);

  r.pair_distance_m.assign(n, 0.0);
  for (size_t i = 1; i < n; ++i) {
    r.pair_distance_m[i] = r.pair_distance_m[i - 1] + (p_gt[i] - p_gt[i - 1]).norm();
    r.est_path_length_m +=
        (T_w_c_aligned[i].translation() - T_w_c_aligned[i - 1].translation()).norm();
  }
  r.gt_path_length_m = r.pair_distance_m.back();

  r.ate = ComputeAte(r.pairs.T_w_c_gt, T_w_c_aligned);
  if (options.alignment != AlignmentType::kNone) {
    const std::string warning = PathAxisRotationWarning(p_gt, r.ate.translation.rmse);
    if (!warning.empty()) r.warnings.push_back(warning);
  }
  // RPE is invariant to the rigid part of the alignment; use the aligned estimate so that a
  // Sim(3) scale applies (what evo_rpe -as does).
  r.has_rpe = ComputeRpe(r.pairs.T_w_c_gt, T_w_c_aligned, options.rpe_delta, options.rpe_delta_unit,
                         &r.rpe);
  // The devkit scores the raw estimate (no scale correction).
  if (options.kitti_segments) {
    r.has_kitti =
        ComputeKittiSegmentErrors(r.pairs.T_w_c_gt, r.pairs.T_w_c_est, options.kitti, &r.kitti);
  }
  r.ok = true;
  return r;
}

namespace {

nlohmann::json StatsJson(const ErrorStatistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},   {"min", s.min},   {"max", s.max}};
}

}  // namespace

nlohmann::json EvalResultToJson(const EvalResult& r) {
  if (!r.ok) return {{"ok", false}, {"error", r.error}};
  nlohmann::json j;
  j["ok"] = true;
  j["pairs"] = r.pairs.size();
  j["paired_by"] = r.pairs.by_index ? "index" : "time";
  j["max_time_diff"] = r.options.max_time_diff_s;
  j["path_length"] = r.gt_path_length_m;
  j["est_path_length"] = r.est_path_length_m;
  j["alignment"] = AlignmentTypeName(r.options.alignment);
  j["scale"] = r.alignment.scale;
  j["warnings"] = r.warnings;
  nlohmann::json ate = StatsJson(r.ate.translation);
  ate["rot_rmse_deg"] = r.ate.rotation_deg.rmse;
  ate["rot_mean_deg"] = r.ate.rotation_deg.mean;
  ate["rot_median_deg"] = r.ate.rotation_deg.median;
  ate["rot_max_deg"] = r.ate.rotation_deg.max;
  j["ate"] = ate;
  if (r.has_rpe) {
    const RpeResult& p = r.rpe;
    j["rpe"] = {{"delta", p.delta},
                {"unit", DeltaUnitName(p.unit)},
                {"pairs", p.index_pairs.size()},
                {"trans_rmse", p.translation.rmse},
                {"trans_mean", p.translation.mean},
                {"trans_median", p.translation.median},
                {"trans_std", p.translation.std},
                {"trans_max", p.translation.max},
                {"rot_rmse_deg", p.rotation_deg.rmse},
                {"rot_mean_deg", p.rotation_deg.mean},
                {"rot_median_deg", p.rotation_deg.median},
                {"rot_max_deg", p.rotation_deg.max}};
  }
  if (r.has_kitti) {
    nlohmann::json per_length = nlohmann::json::array();
    for (const KittiLengthError& le : r.kitti.per_length) {
      per_length.push_back({{"length", le.length_m},
                            {"segments", le.count},
                            {"t_err_percent", le.t_err_percent},
                            {"r_err_deg_per_100m", le.r_err_deg_per_100m}});
    }
    j["kitti"] = {{"t_err_percent", r.kitti.t_err_percent},
                  {"r_err_deg_per_100m", r.kitti.r_err_deg_per_100m},
                  {"segments", r.kitti.segments.size()},
                  {"per_length", per_length}};
  }
  return j;
}

std::string EvalResultToTable(const EvalResult& r) {
  if (!r.ok) return "evaluation failed: " + r.error + "\n";
  std::ostringstream os;
  char line[160];
  const auto row = [&](const char* name, const std::string& value) {
    std::snprintf(line, sizeof(line), "  %-22s %s\n", name, value.c_str());
    os << line;
  };
  const auto num = [](double v, const char* unit, int precision = 6) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), unit[0] != '\0' ? "%.*f %s" : "%.*f%s", precision, v, unit);
    return std::string(buf);
  };
  row("pairs",
      std::to_string(r.pairs.size()) +
          (r.pairs.by_index ? " (by index)"
                            : " (by time, max diff " + num(r.options.max_time_diff_s, "s)", 3)));
  row("path length (gt)", num(r.gt_path_length_m, "m", 3));
  row("alignment", AlignmentTypeName(r.options.alignment));
  row("scale", num(r.alignment.scale, ""));
  os << "ATE (translation)\n";
  row("rmse", num(r.ate.translation.rmse, "m"));
  row("mean", num(r.ate.translation.mean, "m"));
  row("median", num(r.ate.translation.median, "m"));
  row("std", num(r.ate.translation.std, "m"));
  row("min", num(r.ate.translation.min, "m"));
  row("max", num(r.ate.translation.max, "m"));
  row("rotation rmse", num(r.ate.rotation_deg.rmse, "deg", 4));
  if (r.has_rpe) {
    char title[96];
    std::snprintf(title, sizeof(title), "RPE (delta %g %s, %zu pairs)\n", r.rpe.delta,
                  DeltaUnitName(r.rpe.unit), r.rpe.index_pairs.size());
    os << title;
    row("trans rmse", num(r.rpe.translation.rmse, "m"));
    row("trans mean", num(r.rpe.translation.mean, "m"));
    row("trans max", num(r.rpe.translation.max, "m"));
    row("rot rmse", num(r.rpe.rotation_deg.rmse, "deg", 4));
    row("rot mean", num(r.rpe.rotation_deg.mean, "deg", 4));
  } else {
    os << "RPE: no pair for delta " << r.options.rpe_delta << " "
       << DeltaUnitName(r.options.rpe_delta_unit) << "\n";
  }
  if (r.has_kitti) {
    os << "KITTI segments (" << r.kitti.segments.size() << " segments, raw estimate)\n";
    row("t_err", num(r.kitti.t_err_percent, "%", 4));
    row("r_err", num(r.kitti.r_err_deg_per_100m, "deg/100m", 4));
  } else {
    os << "KITTI segments: path too short for a 100 m segment\n";
  }
  for (const std::string& w : r.warnings) os << "note: " << w << "\n";
  return os.str();
}

}  // namespace dala
