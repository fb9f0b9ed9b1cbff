#include "core/eval/kitti_segments.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

namespace dala {

std::vector<double> KittiDevkitLengths() {
  std::vector<double> lengths;
  for (int l = 100; l <= 800; l += 100) lengths.push_back(l);
  return lengths;
}

double KittiRotationError(const Eigen::Matrix3d& R) {
  const double d = 0.5 * (R.trace() - 1.0);
  return std::acos(std::clamp(d, -1.0, 1.0));
}

bool ComputeKittiSegmentErrors(const std::vector<Pose>& T_w_c_gt,
                               const std::vector<Pose>& T_w_c_est,
                               const KittiSegmentOptions& options, KittiSegmentResult* result) {
  CHECK(result != nullptr);
  CHECK_EQ(T_w_c_gt.size(), T_w_c_est.size()) << "KITTI segment errors need paired poses";
  CHECK_GE(options.step_frames, 1);
  *result = KittiSegmentResult();
  const size_t n = T_w_c_gt.size();
  // Path distances along the ground truth.
  std::vector<double> dist(n, 0.0);
  for (size_t k = 1; k < n; ++k) {
    dist[k] = dist[k - 1] + (T_w_c_gt[k].translation() - T_w_c_gt[k - 1].translation()).norm();
  }
  for (size_t first = 0; first < n; first += static_cast<size_t>(options.step_frames)) {
    for (double length : options.lengths_m) {
      // First index whose distance exceeds dist[first] + length (dist is non-decreasing).
      const auto it = std::upper_bound(dist.begin() + static_cast<long>(first), dist.end(),
                                       dist[first] + length);
      if (it == dist.end()) continue;
      const size_t last = static_cast<size_t>(it - dist.begin());
      const Pose delta_gt = T_w_c_gt[first].inverse() * T_w_c_gt[last];
      const Pose delta_est = T_w_c_est[first].inverse() * T_w_c_est[last];
      const Pose E = delta_est.inverse() * delta_gt;
      KittiSegment s;
      s.first = first;
      s.last = last;
      s.length_m = length;
      s.t_err = E.translation().norm() / length;
      s.r_err_rad_per_m = KittiRotationError(E.linear()) / length;
      result->segments.push_back(s);
    }
  }
  if (result->segments.empty()) return false;
  constexpr double kDegPer100mFromRadPerM = 100.0 * 180.0 / M_PI;
  double t_sum = 0.0;
  double r_sum = 0.0;
  for (const KittiSegment& s : result->segments) {
    t_sum += s.t_err;
    r_sum += s.r_err_rad_per_m;
  }
  const double count = static_cast<double>(result->segments.size());
  result->t_err_percent = 100.0 * t_sum / count;
  result->r_err_deg_per_100m = kDegPer100mFromRadPerM * r_sum / count;
  for (double length : options.lengths_m) {
    KittiLengthError le;
    le.length_m = length;
    double t = 0.0;
    double r = 0.0;
    for (const KittiSegment& s : result->segments) {
      if (s.length_m != length) continue;
      ++le.count;
      t += s.t_err;
      r += s.r_err_rad_per_m;
    }
    if (le.count == 0) continue;
    le.t_err_percent = 100.0 * t / static_cast<double>(le.count);
    le.r_err_deg_per_100m = kDegPer100mFromRadPerM * r / static_cast<double>(le.count);
    result->per_length.push_back(le);
  }
  return true;
}

}  // namespace dala
