#include "backend/ba/disparity_offset_calibration.h"

#include <algorithm>
#include <cmath>

namespace dala {

bool DisparityOffsetCalibration::Options::IsValid(std::string* why) const {
  auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (min_estimates < 2) return fail("offset_calibration_min_estimates must be >= 2");
  if (!(bias_px > 0.0)) return fail("offset_calibration_bias_px must be > 0");
  if (converged_after_estimates < min_estimates) {
    return fail(
        "offset_calibration_converged_after_estimates must be >= "
        "offset_calibration_min_estimates");
  }
  if (!(stable_px >= 0.0)) return fail("offset_calibration_stable_px must be >= 0");
  if (!(min_window_span_baselines >= 0.0)) {
    return fail("offset_calibration_min_window_span_baselines must be >= 0");
  }
  if (!(max_prior_offset_change_px >= 0.0)) {
    return fail("offset_calibration_max_prior_offset_change_px must be >= 0");
  }
  return true;
}

void DisparityOffsetCalibration::Add(double estimate_px) {
  if (converged_ || !std::isfinite(estimate_px)) return;
  ++n_;
  estimates_.push_back(estimate_px);
  std::vector<double> sorted = estimates_;
  std::sort(sorted.begin(), sorted.end());
  const size_t k = sorted.size() / 2;
  median_px_ = sorted.size() % 2 == 1 ? sorted[k] : 0.5 * (sorted[k - 1] + sorted[k]);
  if (n_ < options_.min_estimates) return;
  const double b = options_.bias_px;
  const double weight = std::clamp((std::abs(median_px_) - b) / b, 0.0, 1.0);
  offset_px_ = weight > 0.0 ? weight * median_px_ : 0.0;  // not -0.0
  recent_medians_.push_back(median_px_);
  if (static_cast<int>(recent_medians_.size()) > options_.min_estimates) {
    recent_medians_.pop_front();
  }
  converged_ = n_ >= options_.converged_after_estimates &&
               static_cast<int>(recent_medians_.size()) == options_.min_estimates &&
               std::abs(recent_medians_.back() - recent_medians_.front()) <= options_.stable_px;
}

}  // namespace dala
