#include "core/sim/recorded_path.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace dala::sim {
namespace {

// A path's climbs and descents over more than this much travel either side are levelled out.
constexpr double kLevellingHalfWindowM = 25.0;

}  // namespace

std::vector<StampedPose> PlaceOnStreet(const std::vector<StampedPose>& path, double camera_height) {
  if (path.size() < 2) {
    throw Error() << "a path to render along needs at least 2 poses, got " << path.size();
  }
  if (!(camera_height > 0.0 && camera_height <= 100.0)) {
    throw Error() << "the camera height above the street must be in (0, 100] m, got "
                  << camera_height;
  }
  Eigen::Vector3d down_sum = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < path.size(); ++i) {
    if (i > 0 && path[i].t_ns <= path[i - 1].t_ns) {
      throw Error() << "the path's times must increase: pose " << i << " is at "
                    << SecondsFromNs(path[i].t_ns) << " s, pose " << i - 1 << " at "
                    << SecondsFromNs(path[i - 1].t_ns) << " s";
    }
    down_sum += path[i].T_w_c.linear().col(1);
  }
  // |mean of unit vectors| is 1 when every camera's y axis points the same way.
  const double resultant = down_sum.norm() / static_cast<double>(path.size());
  if (resultant < 0.8) {
    throw Error() << "the path's cameras do not share a down direction (mean of their y axes "
                  << resultant
                  << " long, 1 = all alike): the street world takes a car's or a rover's path, "
                     "cameras looking roughly horizontally";
  }
  const Eigen::Vector3d up = -down_sum.normalized();
  // x: the first camera's viewing direction on the horizontal plane (or any horizontal axis if
  // it looks straight up or down).
  Eigen::Vector3d x = path[0].T_w_c.linear().col(2);
  x -= x.dot(up) * up;
  if (x.norm() < 1e-6) x = up.unitOrthogonal();
  x.normalize();
  Eigen::Matrix3d R_s_w;
  R_s_w.row(0) = x.transpose();
  R_s_w.row(1) = up.cross(x).transpose();
  R_s_w.row(2) = up.transpose();

  // Heights along the path, and their mean over kLevellingHalfWindowM of travel either side.
  const Eigen::Vector3d p_w0 = path[0].T_w_c.translation();
  const size_t n = path.size();
  std::vector<double> height(n), arc(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    height[i] = up.dot(path[i].T_w_c.translation() - p_w0);
    if (i > 0) {
      arc[i] = arc[i - 1] + (path[i].T_w_c.translation() - path[i - 1].T_w_c.translation()).norm();
    }
  }
  std::vector<StampedPose> placed;
  placed.reserve(n);
  size_t lo = 0, hi = 0;  // The poses within the window around i: [lo, hi).
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    while (hi < n && arc[hi] <= arc[i] + kLevellingHalfWindowM) sum += height[hi++];
    while (arc[lo] < arc[i] - kLevellingHalfWindowM) sum -= height[lo++];
    const double level = sum / static_cast<double>(hi - lo);
    Eigen::Vector3d p_s = R_s_w * (path[i].T_w_c.translation() - p_w0);
    p_s.z() = camera_height + height[i] - level;
    placed.push_back({path[i].t_ns - path[0].t_ns, MakePose(R_s_w * path[i].T_w_c.linear(), p_s)});
  }
  return placed;
}

RecordedPath::RecordedPath(std::vector<StampedPose> poses) : poses_(std::move(poses)) {
  CHECK(!poses_.empty()) << "a recorded path needs at least one pose";
  for (size_t i = 1; i < poses_.size(); ++i) CHECK_GT(poses_[i].t_ns, poses_[i - 1].t_ns);
}

double RecordedPath::duration_s() const {
  return SecondsFromNs(poses_.back().t_ns - poses_.front().t_ns);
}

Pose RecordedPath::T_w_c(double t_s) const {
  const int64_t t_ns = poses_.front().t_ns + NsFromSeconds(t_s);
  if (t_ns <= poses_.front().t_ns) return poses_.front().T_w_c;
  if (t_ns >= poses_.back().t_ns) return poses_.back().T_w_c;
  const auto after = std::upper_bound(poses_.begin(), poses_.end(), t_ns,
                                      [](int64_t t, const StampedPose& p) { return t < p.t_ns; });
  const StampedPose& b = *after;
  const StampedPose& a = *std::prev(after);
  const double s = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  return InterpolatePose(a.T_w_c, b.T_w_c, s);
}

}  // namespace dala::sim
