#include "core/eval/association.h"

#include <glog/logging.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <sstream>
#include <tuple>

#include "core/trajectory.h"

namespace dala {
namespace {

std::string TimeRange(const Trajectory& t) {
  std::ostringstream os;
  os.precision(6);
  os << std::fixed << "[" << SecondsFromNs(t.poses.front().t_ns) << ", "
     << SecondsFromNs(t.poses.back().t_ns) << "] s";
  return os.str();
}

}  // namespace

std::vector<PoseMatch> AssociateByTime(const Trajectory& gt, const Trajectory& est,
                                       int64_t max_diff_ns) {
  CHECK_GE(max_diff_ns, 0) << "max_diff_ns must be non-negative";
  // Ground truth indices sorted by time (the readers give sorted stamps; do not rely on it).
  std::vector<size_t> gt_order(gt.size());
  std::iota(gt_order.begin(), gt_order.end(), size_t{0});
  std::stable_sort(gt_order.begin(), gt_order.end(),
                   [&](size_t a, size_t b) { return gt.poses[a].t_ns < gt.poses[b].t_ns; });
  std::vector<int64_t> gt_t(gt.size());
  for (size_t k = 0; k < gt_order.size(); ++k) gt_t[k] = gt.poses[gt_order[k]].t_ns;

  // Candidates (|dt|, est, gt) within the window, found by binary search on the sorted stamps.
  std::vector<std::tuple<int64_t, size_t, size_t>> candidates;
  for (size_t i = 0; i < est.size(); ++i) {
    const int64_t t = est.poses[i].t_ns;
    auto it = std::lower_bound(gt_t.begin(), gt_t.end(), t - max_diff_ns);
    for (; it != gt_t.end() && *it <= t + max_diff_ns; ++it) {
      const size_t k = static_cast<size_t>(it - gt_t.begin());
      candidates.emplace_back(std::llabs(*it - t), i, gt_order[k]);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> est_used(est.size(), false);
  std::vector<bool> gt_used(gt.size(), false);
  std::vector<PoseMatch> matches;
  for (const auto& [dt, i, j] : candidates) {
    if (est_used[i] || gt_used[j]) continue;
    est_used[i] = true;
    gt_used[j] = true;
    matches.push_back({j, i});
  }
  std::sort(matches.begin(), matches.end(),
            [](const PoseMatch& a, const PoseMatch& b) { return a.est < b.est; });
  return matches;
}

bool PairTrajectories(const Trajectory& gt, const Trajectory& est, double max_diff_s,
                      PairedPoses* pairs, std::string* why) {
  CHECK(pairs != nullptr);
  *pairs = PairedPoses();
  const auto fail = [&](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (gt.empty() || est.empty()) {
    return fail(std::string("the ") + (gt.empty() ? "ground truth" : "estimate") +
                " trajectory is empty");
  }
  if (gt.has_timestamps != est.has_timestamps) {
    return fail(std::string("the ") + (gt.has_timestamps ? "estimate" : "ground truth") +
                " has no timestamps (KITTI format) but the " +
                (gt.has_timestamps ? "ground truth" : "estimate") +
                " has: give a times file for it (--times) or use the same format for both");
  }
  if (!gt.has_timestamps) {
    if (gt.size() != est.size()) {
      std::ostringstream os;
      os << "trajectories without timestamps (KITTI) pair by row index and need equal lengths, "
         << "but the ground truth has " << gt.size() << " poses and the estimate " << est.size()
         << ": give a times file (--times) to associate by time";
      return fail(os.str());
    }
    pairs->by_index = true;
    for (size_t i = 0; i < gt.size(); ++i) pairs->matches.push_back({i, i});
  } else {
    pairs->matches = AssociateByTime(gt, est, NsFromSeconds(max_diff_s));
    if (pairs->matches.empty()) {
      std::ostringstream os;
      os << "no pose of the estimate has a ground truth stamp within max diff " << max_diff_s
         << " s: the ground truth spans " << TimeRange(gt) << " (" << gt.size()
         << " poses), the estimate " << TimeRange(est) << " (" << est.size()
         << " poses); check that both use the same clock and units, or raise --max_diff";
      return fail(os.str());
    }
  }
  for (const PoseMatch& m : pairs->matches) {
    pairs->t_ns.push_back(est.poses[m.est].t_ns);
    pairs->T_w_c_gt.push_back(gt.poses[m.gt].T_w_c);
    pairs->T_w_c_est.push_back(est.poses[m.est].T_w_c);
  }
  return true;
}

}  // namespace dala
