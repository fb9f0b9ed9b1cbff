#include "core/trajectory.h"

#include <cmath>

namespace dala {

double Trajectory::PathLength() const {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) {
    length += (poses[i].T_w_c.translation() - poses[i - 1].T_w_c.translation()).norm();
  }
  return length;
}

int64_t NsFromSeconds(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e9)); }

}  // namespace dala
