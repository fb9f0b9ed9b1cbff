#ifndef DALA_BACKEND_BA_RELATIVE_POSE_COST_H_
#define DALA_BACKEND_BA_RELATIVE_POSE_COST_H_

// A measured relative pose T_a_b between two pose blocks (backend/ba/pose_block.h), the factor of
// the pose graphs and of the window's relative-pose priors:
//   T_err = T_a_b_meas^-1 * (T_w_a^-1 * T_w_b),   e = [2 vec(q_err); t_err]   (6, [rot; trans])
//   r = sqrt_info * e,   sqrt_info^T sqrt_info = information (6x6, [rotation; translation]).
// e equals Log(T_err) = [phi; rho] to first order, the right-perturbation error of the
// measurement in the frame b, so `information` is the inverse covariance of T_a_b_meas in dala's
// convention (core/geometry.h). Automatic derivatives (this file's .cc is their one translation
// unit).

#include <ceres/cost_function.h>

#include "core/geometry.h"

namespace dala {

// A new cost on the blocks (x_a, x_b); the caller (or the ceres::Problem) owns it.
ceres::CostFunction* CreateRelativePoseCost(const Pose& T_a_b_meas, const Matrix6d& sqrt_info);

}  // namespace dala

#endif  // DALA_BACKEND_BA_RELATIVE_POSE_COST_H_
