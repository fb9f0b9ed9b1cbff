#ifndef DALA_TESTS_CORE_EVAL_EVAL_TEST_UTIL_H_
#define DALA_TESTS_CORE_EVAL_EVAL_TEST_UTIL_H_

#include <cmath>

#include "core/eval/alignment.h"
#include "core/geometry.h"
#include "core/trajectory.h"

namespace dala::testing {

// A smooth 3D trajectory that turns and climbs: n poses, 10 Hz stamps from t0.
inline Trajectory HelixTrajectory(int n, int64_t t0_ns = 1000000000LL) {
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    const double a = 0.05 * i;
    const Eigen::Vector3d p(10.0 * std::cos(a), 10.0 * std::sin(a), 0.1 * i);
    const Eigen::Matrix3d R = ExpSO3(Eigen::Vector3d(0.1 * std::sin(a), 0.05, a));
    t.Add(t0_ns + i * 100000000LL, MakePose(R, p));
  }
  return t;
}

// The trajectory in another world and unit, p -> s R p + t with R = Exp(rotvec) (a monocular
// run's own frame; orientations turn by R).
inline Trajectory Transformed(const Trajectory& in, double s, const Eigen::Vector3d& rotvec,
                              const Eigen::Vector3d& t) {
  Sim3Alignment S;
  S.scale = s;
  S.T_g_e.linear() = ExpSO3(rotvec);
  S.T_g_e.translation() = t;
  return AlignTrajectory(in, S);
}

}  // namespace dala::testing

#endif  // DALA_TESTS_CORE_EVAL_EVAL_TEST_UTIL_H_
