#ifndef DALA_CORE_EVAL_RPE_H_
#define DALA_CORE_EVAL_RPE_H_

#include <string>
#include <utility>
#include <vector>

#include "core/eval/statistics.h"
#include "core/geometry.h"

namespace dala {

// The unit of the RPE step delta.
enum class DeltaUnit { kFrames, kMetres };
const char* DeltaUnitName(DeltaUnit unit);  // "frames", "metres"
// Parses "f", "frames", "m", "metres", "meters"; false for anything else.
bool ParseDeltaUnit(const std::string& name, DeltaUnit* unit);

// Relative pose error as evo_rpe computes it with its defaults (consecutive pairs, i.e.
// all_pairs = false; pairs chosen on the estimate):
//  - kFrames: ids 0, d, 2d, ...; pairs (0, d), (d, 2d), ...
//  - kMetres: walking along the estimate, a pose becomes an id each time the path travelled since
//    the previous id (or since pose 0 for the first one) reaches delta; pairs are consecutive ids.
// For a pair (i, j) with ground truth P and estimate Q (world <- camera poses):
//   E = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j),
// translation error |t(E)| (metres), rotation error angle(R(E)) (degrees). E is invariant to a
// rigid alignment of either trajectory; a Sim(3) scale of the estimate does change it.
struct RpeResult {
  double delta = 1.0;
  DeltaUnit unit = DeltaUnit::kFrames;
  std::vector<std::pair<size_t, size_t>> index_pairs;  // (i, j) into the paired poses.
  std::vector<double> translation_errors;              // Metres, one per index pair.
  std::vector<double> rotation_errors_deg;             // Degrees, one per index pair.
  ErrorStatistics translation;
  ErrorStatistics rotation_deg;
};

// The index pairs of evo's consecutive-pairs mode (see above), chosen on `T_w_c`.
std::vector<std::pair<size_t, size_t>> RpeIndexPairs(const std::vector<Pose>& T_w_c, double delta,
                                                     DeltaUnit unit);

// Computes the RPE of paired poses (same length, CHECKed). Returns false when delta gives no
// pair (the trajectory is shorter than two steps); `rpe` then holds no errors.
bool ComputeRpe(const std::vector<Pose>& T_w_c_gt, const std::vector<Pose>& T_w_c_est, double delta,
                DeltaUnit unit, RpeResult* rpe);

}  // namespace dala

#endif  // DALA_CORE_EVAL_RPE_H_
