#include "backend/mono/loop_sim3.h"

#include <glog/logging.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace dala {
namespace {

// Umeyama with scaling on the pairs `index` (3 or more).
std::optional<Sim3> FitSim3(const std::vector<Eigen::Vector3d>& p_cur,
                            const std::vector<Eigen::Vector3d>& p_old,
                            const std::vector<int>& index) {
  Eigen::Matrix3Xd src(3, index.size()), dst(3, index.size());
  for (size_t k = 0; k < index.size(); ++k) {
    src.col(k) = p_cur[index[k]];
    dst.col(k) = p_old[index[k]];
  }
  const Eigen::Matrix4d M = Eigen::umeyama(src, dst, true);
  const Eigen::Matrix3d sR = M.topLeftCorner<3, 3>();
  const double scale = sR.col(0).norm();
  if (!(scale > 1e-9) || !M.allFinite()) return std::nullopt;  // Degenerate (collinear) sample.
  Sim3 S;
  S.scale = scale;
  S.T = MakePose(sR / scale, M.topRightCorner<3, 1>());
  return S;
}

int CountInliers(const Sim3& S, const std::vector<Eigen::Vector3d>& p_cur,
                 const std::vector<Eigen::Vector3d>& p_old, const Eigen::Vector3d& c_cur,
                 double relative_tolerance, std::vector<bool>* inlier) {
  inlier->assign(p_cur.size(), false);
  int n = 0;
  for (size_t i = 0; i < p_cur.size(); ++i) {
    const double tolerance = relative_tolerance * S.scale * (p_cur[i] - c_cur).norm();
    if ((p_old[i] - S * p_cur[i]).norm() <= tolerance) {
      (*inlier)[i] = true;
      ++n;
    }
  }
  return n;
}

}  // namespace

bool LoopSim3Options::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (ransac_iterations < 1) return fail("loop_sim3.ransac_iterations must be >= 1");
  if (!(relative_tolerance > 0.0)) return fail("loop_sim3.relative_tolerance must be > 0");
  if (min_inliers < 3) return fail("loop_sim3.min_inliers must be >= 3");
  return true;
}

std::optional<LoopSim3> EstimateLoopSim3(const std::vector<Eigen::Vector3d>& p_cur,
                                         const std::vector<Eigen::Vector3d>& p_old,
                                         const Eigen::Vector3d& camera_centre_cur,
                                         const LoopSim3Options& options) {
  CHECK_EQ(p_cur.size(), p_old.size());
  const int n = static_cast<int>(p_cur.size());
  if (n < options.min_inliers) return std::nullopt;
  std::mt19937 rng(static_cast<std::mt19937::result_type>(options.seed));
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::optional<LoopSim3> best;
  std::vector<bool> inlier;
  for (int it = 0; it < options.ransac_iterations; ++it) {
    const int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    const std::optional<Sim3> S = FitSim3(p_cur, p_old, {a, b, c});
    if (!S) continue;
    const int count =
        CountInliers(*S, p_cur, p_old, camera_centre_cur, options.relative_tolerance, &inlier);
    if (!best || count > best->inliers) best = LoopSim3{*S, count, inlier};
  }
  if (!best || best->inliers < std::max(3, options.min_inliers)) return std::nullopt;
  // Refit on the inliers, then once more on the refit's inliers.
  for (int round = 0; round < 2; ++round) {
    std::vector<int> index;
    for (int i = 0; i < n; ++i) {
      if (best->inlier[i]) index.push_back(i);
    }
    const std::optional<Sim3> S = FitSim3(p_cur, p_old, index);
    if (!S) break;
    const int count =
        CountInliers(*S, p_cur, p_old, camera_centre_cur, options.relative_tolerance, &inlier);
    if (count < best->inliers) break;
    best = LoopSim3{*S, count, inlier};
  }
  if (best->inliers < options.min_inliers) return std::nullopt;
  return best;
}

}  // namespace dala
