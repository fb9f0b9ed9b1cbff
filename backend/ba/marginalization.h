#ifndef DALA_BACKEND_BA_MARGINALIZATION_H_
#define DALA_BACKEND_BA_MARGINALIZATION_H_

// Marginalisation of states leaving the sliding window into a linear prior on the states that
// stay (the Schur complement of the linearised system).
//
// Math. Let the factors touching the leaving states be stacked as whitened residuals r(x), with
// Jacobian J in the manifold tangent of every variable block (poses: backend/ba/pose_block.h;
// landmarks: R^3), evaluated ONCE at the current estimate x_lin. Robust losses enter by the
// IRLS weight sqrt(rho'(|r_i|^2)) on each block's residual and Jacobian (the second-order term
// of the loss is dropped, which keeps H positive semi-definite). The Gauss-Newton system
//   H = J^T J,  b = J^T r,   ordered as [m (marginalised) | k (kept)]
// is reduced in two steps, both exact Schur complements:
//   1. every marginalised landmark l (3x3 block, seen by poses only):
//        H_pp -= H_pl H_ll^+ H_lp,  b_p -= H_pl H_ll^+ b_l   (p = all pose variables),
//   2. the marginalised pose(s) m:
//        H* = H_kk - H_km H_mm^+ H_mk,  b* = b_k - H_km H_mm^+ b_m,
// with ^+ the pseudo-inverse by eigen-decomposition (eigenvalues below a floor are zeroed, so
// an unobservable direction adds no information instead of infinite information).
// The prior keeps 0.5 |r_p|^2 = 0.5 d^T H* d + b*^T d + const with d = x_k [-] x_lin (the manifold
// Minus, stacked over the kept poses). With H* = V L V^T and the eigenvalues L_i above the floor:
//   S = L^{1/2} V^T  (rank x 6k),   r0 = L^{-1/2} V^T b*,   r_p(x) = S d(x) + r0.
// The linearisation point x_lin stays fixed for the life of the prior (first-estimate
// Jacobians): the prior is linear in d, and later marginalisations feed it back as a factor.
//
// Constant parameter blocks (gauge-fixed keyframes) take part as constants: they get no
// columns, so their information goes nowhere, which is what fixing them means.

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <vector>

#include "backend/ba/pose_block.h"
#include "core/types.h"

namespace dala {

// A linear prior on keyframe poses, the result of Marginalize().
struct MarginalizationPrior {
  std::vector<KeyframeId> keyframes;  // the pose blocks it constrains, in column order.
  std::vector<PoseBlock> x_lin;       // their linearisation points.
  Eigen::MatrixXd sqrt_information;   // S, rank x (6 * keyframes.size()).
  Eigen::VectorXd r0;                 // rank.

  bool empty() const { return keyframes.empty() || sqrt_information.rows() == 0; }
  int rank() const { return static_cast<int>(sqrt_information.rows()); }
};

// The prior residual r_p(x) = S (x [-] x_lin) + r0 as a Ceres cost function over one 7-vector
// pose block per prior.keyframes entry, in that order (autodiff, dynamic sizes).
ceres::CostFunction* CreatePriorCost(const MarginalizationPrior& prior);

// The manifold Minus of two pose blocks, d = y [-] x in the pose tangent (pose_block.h).
Vector6d PoseBlockMinus(const double* y, const double* x);

// One factor of the linearised system: a cost function, its (optional) robust loss and its
// parameter blocks, exactly as they would be given to ceres::Problem::AddResidualBlock.
struct FactorRef {
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;  // may be null.
  std::vector<double*> blocks;
};

struct MarginalizationInput {
  std::vector<FactorRef> factors;               // every factor touching a marginalised state.
  std::vector<double*> marginalized_poses;      // 7-vector pose blocks to remove.
  std::vector<double*> marginalized_landmarks;  // 3-vector blocks to remove.
  std::vector<std::pair<KeyframeId, double*>> kept_poses;  // variable pose blocks that stay.
  // Any other block met in a factor is a constant.
  double eigenvalue_floor = 1e-8;  // relative to the largest eigenvalue (and absolute 1e-12).
};

// Builds the prior on the kept poses (those a factor actually connects). CHECKs that each
// factor's blocks are listed or constant and that evaluation succeeds (a broken invariant).
MarginalizationPrior Marginalize(const MarginalizationInput& input);

}  // namespace dala

#endif  // DALA_BACKEND_BA_MARGINALIZATION_H_
