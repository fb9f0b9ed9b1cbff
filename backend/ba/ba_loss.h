#ifndef DALA_BACKEND_BA_BA_LOSS_H_
#define DALA_BACKEND_BA_BA_LOSS_H_

// Robust loss choice shared by the BA, pose-only and pose-graph options.

#include <ceres/loss_function.h>

#include <memory>
#include <string>

namespace dala {

enum class RobustLoss { kNone, kHuber, kCauchy };

// The Ceres loss rho(s) on the squared whitened norm s of one residual block, with scale a:
// Huber is quadratic for s <= a^2, Cauchy is a^2 log(1 + s / a^2). kNone returns null.
std::unique_ptr<ceres::LossFunction> MakeLoss(RobustLoss loss, double scale);

}  // namespace dala

#endif  // DALA_BACKEND_BA_BA_LOSS_H_
