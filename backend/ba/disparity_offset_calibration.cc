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
  if (!(min_offset_px >= 0.0)) return fail("offset_calibration_min_offset_px must be >= 0");
  if (!(min_mean_over_sd >= 0.0)) return fail("offset_calibration_min_mean_over_sd must be >= 0");
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
  sum_ += estimate_px;
  sum_sq_ += estimate_px * estimate_px;
  if (n_ < options_.min_estimates) return;
  const double mean = sum_ / n_;
  const double sd = std::sqrt(std::max(0.0, sum_sq_ / n_ - mean * mean));
  const bool beyond_bias = std::abs(mean) >= options_.min_offset_px;
  const bool agreed = std::abs(mean) >= options_.min_mean_over_sd * sd;
  if (beyond_bias && agreed) {
    offset_px_ = mean;
  }
  recent_means_.push_back(mean);
  if (static_cast<int>(recent_means_.size()) > options_.min_estimates) recent_means_.pop_front();
  converged_ = n_ >= options_.converged_after_estimates &&
               static_cast<int>(recent_means_.size()) == options_.min_estimates &&
               std::abs(recent_means_.back() - recent_means_.front()) <= options_.stable_px;
}

}  // namespace dala
