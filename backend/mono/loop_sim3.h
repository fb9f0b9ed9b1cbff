#ifndef DALA_BACKEND_MONO_LOOP_SIM3_H_
#define DALA_BACKEND_MONO_LOOP_SIM3_H_

// The similarity between two estimates of the same place in a monocular map: the landmarks the
// place recognition matched (current landmark <-> old landmark, frontend/place_recognition.h),
// each with a position in the current neighbourhood of the map (whose scale has drifted) and
// one in the old neighbourhood. Finds S (world_cur -> world_old) with
//   p_old = s R p_cur + t
// by RANSAC over minimal 3-point samples (Eigen::umeyama with scaling, Umeyama 1991), then a
// refit on the inliers. A pair is an inlier when |p_old - S p_cur| <= relative_tolerance * s *
// |p_cur - c_cur|, c_cur the current camera centre: a monocular point's error grows with its
// distance. Deterministic (std::mt19937 seeded from the options).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "backend/ba/sim3_pose_graph.h"

namespace dala {

struct LoopSim3Options {
  int ransac_iterations = 300;
  double relative_tolerance = 0.05;
  int min_inliers = 15;
  uint64_t seed = 42;

  bool IsValid(std::string* why) const;
};

struct LoopSim3 {
  Sim3 S_old_cur;  // world_cur -> world_old.
  int inliers = 0;
  std::vector<bool> inlier;  // Per pair.
};

// nullopt with fewer than min_inliers inliers (or fewer pairs).
std::optional<LoopSim3> EstimateLoopSim3(const std::vector<Eigen::Vector3d>& p_cur,
                                         const std::vector<Eigen::Vector3d>& p_old,
                                         const Eigen::Vector3d& camera_centre_cur,
                                         const LoopSim3Options& options);

}  // namespace dala

#endif  // DALA_BACKEND_MONO_LOOP_SIM3_H_
