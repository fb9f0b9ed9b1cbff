#ifndef DALA_CORE_EVAL_ALIGNMENT_H_
#define DALA_CORE_EVAL_ALIGNMENT_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/trajectory.h"

namespace dala {

// How the estimate is brought into the ground truth world before the absolute error:
// none, a rigid transform (SE(3)), or a similarity (Sim(3), for monocular scale).
enum class AlignmentType { kNone, kSE3, kSim3 };

const char* AlignmentTypeName(AlignmentType type);  // "none", "se3", "sim3"
// Parses "none", "se3", "sim3" (case-insensitive); false for anything else.
bool ParseAlignmentType(const std::string& name, AlignmentType* type);

// A similarity from the estimate's world e to the ground truth world g:
//   p_g = scale * R_g_e * p_e + t_g_e,
// applied to a pose T_e_c as T_g_c = [R_g_e * R_e_c | scale * R_g_e * t_e_c + t_g_e] (the scale
// changes positions only, orientations stay rotations).
struct Sim3Alignment {
  double scale = 1.0;
  Pose T_g_e = Pose::Identity();  // Rotation R_g_e and translation t_g_e.

  Eigen::Vector3d Apply(const Eigen::Vector3d& p_e) const {
    return scale * (T_g_e.linear() * p_e) + T_g_e.translation();
  }
  Pose Apply(const Pose& T_e_c) const;
};

// Least-squares alignment of the positions p_e (estimate) onto p_g (ground truth, same order) by
// Umeyama's method (Eigen::umeyama), minimising sum |p_g - (s R p_e + t)|^2 with s fixed to 1 for
// SE(3). kNone gives the identity. Returns false (and says why) when the points allow no unique
// answer: fewer than 3 pairs, or (Sim(3)) all estimated positions equal.
bool ComputeAlignment(const std::vector<Eigen::Vector3d>& p_e,
                      const std::vector<Eigen::Vector3d>& p_g, AlignmentType type,
                      Sim3Alignment* alignment, std::string* why);

// The estimate with every pose mapped into the ground truth world (stamps kept).
Trajectory AlignTrajectory(const Trajectory& est, const Sim3Alignment& alignment);

}  // namespace dala

#endif  // DALA_CORE_EVAL_ALIGNMENT_H_
