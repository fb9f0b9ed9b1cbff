#ifndef DALA_CORE_EVAL_ATE_H_
#define DALA_CORE_EVAL_ATE_H_

#include <vector>

#include "core/eval/statistics.h"
#include "core/geometry.h"

namespace dala {

// Absolute trajectory error of paired poses, the estimate already aligned into the ground
// truth world (see alignment.h). For pair i:
//   translation error e_i = |t_gt_i - t_est_i|                       (metres)
//   rotation error    a_i = angle(R_gt_i^T * R_est_i)                (degrees, in [0, 180])
// This is evo_ape's "translation part" and "rotation angle" relations.
struct AteResult {
  std::vector<double> translation_errors;   // One per pair, metres.
  std::vector<double> rotation_errors_deg;  // One per pair, degrees.
  ErrorStatistics translation;
  ErrorStatistics rotation_deg;
};

// gt and aligned_est must have the same length (CHECKed).
AteResult ComputeAte(const std::vector<Pose>& T_w_c_gt, const std::vector<Pose>& T_w_c_est_aligned);

// The rotation angle of R in degrees, in [0, 180] (|log R|, numerically stable near 0).
double RotationAngleDeg(const Eigen::Matrix3d& R);

}  // namespace dala

#endif  // DALA_CORE_EVAL_ATE_H_
