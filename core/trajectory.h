#ifndef DALA_CORE_TRAJECTORY_H_
#define DALA_CORE_TRAJECTORY_H_

#include <cstdint>
#include <vector>

#include "core/geometry.h"

namespace dala {

// One timestamped pose T_w_c (camera in world).
struct StampedPose {
  int64_t t_ns = 0;
  Pose T_w_c = Pose::Identity();
};

// A trajectory: poses in increasing time order. KITTI files carry no timestamps; a trajectory
// read from one has has_timestamps == false and t_ns holds the row index (in seconds as ns,
// i.e. row i -> i * 1e9) until a times file is applied.
struct Trajectory {
  std::vector<StampedPose> poses;
  bool has_timestamps = true;

  size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
  void Add(int64_t t_ns, const Pose& T_w_c) { poses.push_back({t_ns, T_w_c}); }
  // Total length of the path through the positions, in metres.
  double PathLength() const;
};

inline double SecondsFromNs(int64_t t_ns) { return static_cast<double>(t_ns) * 1e-9; }
// Rounds to the nearest nanosecond (a TUM timestamp has at most ~9 significant decimals).
int64_t NsFromSeconds(double seconds);

}  // namespace dala

#endif  // DALA_CORE_TRAJECTORY_H_
