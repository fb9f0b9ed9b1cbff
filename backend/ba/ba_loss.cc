#include "backend/ba/ba_loss.h"

namespace dala {

std::unique_ptr<ceres::LossFunction> MakeLoss(RobustLoss loss, double scale) {
  switch (loss) {
    case RobustLoss::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale);
    case RobustLoss::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale);
    case RobustLoss::kNone:
      break;
  }
  return nullptr;
}

}  // namespace dala
