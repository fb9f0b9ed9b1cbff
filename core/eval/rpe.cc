#include "core/eval/rpe.h"

#include <glog/logging.h>

#include <cmath>

#include "core/eval/ate.h"

namespace dala {

const char* DeltaUnitName(DeltaUnit unit) {
  return unit == DeltaUnit::kFrames ? "frames" : "metres";
}

bool ParseDeltaUnit(const std::string& name, DeltaUnit* unit) {
  if (name == "f" || name == "frames" || name == "frame") {
    *unit = DeltaUnit::kFrames;
    return true;
  }
  if (name == "m" || name == "metres" || name == "meters") {
    *unit = DeltaUnit::kMetres;
    return true;
  }
  return false;
}

std::vector<std::pair<size_t, size_t>> RpeIndexPairs(const std::vector<Pose>& T_w_c, double delta,
                                                     DeltaUnit unit) {
  CHECK_GT(delta, 0.0) << "RPE delta must be positive";
  std::vector<size_t> ids;
  if (unit == DeltaUnit::kFrames) {
    const size_t step = static_cast<size_t>(std::llround(delta));
    CHECK_GE(step, 1u) << "RPE delta in frames must be an integer >= 1";
    for (size_t i = 0; i < T_w_c.size(); i += step) ids.push_back(i);
  } else {
    // Path travelled since the last id; the first id is where it first reaches delta (evo's
    // filter_pairs_by_path without all_pairs, which starts counting at pose 0).
    double travelled = 0.0;
    for (size_t i = 0; i < T_w_c.size(); ++i) {
      if (i > 0) travelled += (T_w_c[i].translation() - T_w_c[i - 1].translation()).norm();
      if (travelled >= delta) {
        ids.push_back(i);
        travelled = 0.0;
      }
    }
  }
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  return pairs;
}

bool ComputeRpe(const std::vector<Pose>& T_w_c_gt, const std::vector<Pose>& T_w_c_est, double delta,
                DeltaUnit unit, RpeResult* rpe) {
  CHECK(rpe != nullptr);
  CHECK_EQ(T_w_c_gt.size(), T_w_c_est.size()) << "RPE needs paired poses";
  *rpe = RpeResult();
  rpe->delta = delta;
  rpe->unit = unit;
  rpe->index_pairs = RpeIndexPairs(T_w_c_est, delta, unit);
  for (const auto& [i, j] : rpe->index_pairs) {
    const Pose T_ci_cj_gt = T_w_c_gt[i].inverse() * T_w_c_gt[j];
    const Pose T_ci_cj_est = T_w_c_est[i].inverse() * T_w_c_est[j];
    const Pose E = T_ci_cj_gt.inverse() * T_ci_cj_est;
    rpe->translation_errors.push_back(E.translation().norm());
    rpe->rotation_errors_deg.push_back(RotationAngleDeg(E.linear()));
  }
  rpe->translation = ComputeStatistics(rpe->translation_errors);
  rpe->rotation_deg = ComputeStatistics(rpe->rotation_errors_deg);
  return !rpe->index_pairs.empty();
}

}  // namespace dala
