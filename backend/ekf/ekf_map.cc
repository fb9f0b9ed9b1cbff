#include "backend/ekf/ekf_map.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

namespace dala {

ImageGrid::ImageGrid(int width, int height, int cols, int rows)
    : width_(width), height_(height), cols_(cols), rows_(rows) {
  CHECK_GT(width, 0);
  CHECK_GT(height, 0);
  CHECK_GE(cols, 1);
  CHECK_GE(rows, 1);
}

int ImageGrid::Zone(const Eigen::Vector2d& uv) const {
  const int col = std::clamp(static_cast<int>(std::floor(uv.x() / width_ * cols_)), 0, cols_ - 1);
  const int row = std::clamp(static_cast<int>(std::floor(uv.y() / height_ * rows_)), 0, rows_ - 1);
  return row * cols_ + col;
}

std::vector<int> EvictionOrder(const EkfState& state, const EkfLandmarkInfoMap& info, int frame,
                               int min_unseen_frames) {
  std::vector<int> order;
  for (int i = 0; i < state.num_landmarks(); ++i) {
    if (frame - info.at(state.id(i)).last_seen >= min_unseen_frames) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const EkfLandmarkInfo& ia = info.at(state.id(a));
    const EkfLandmarkInfo& ib = info.at(state.id(b));
    if (ia.observations != ib.observations) return ia.observations < ib.observations;
    if (ia.created != ib.created) return ia.created > ib.created;
    return a < b;
  });
  return order;
}

std::vector<MapPoint> EkfMapPoints(const EkfState& state, const EkfLandmarkInfoMap& info) {
  std::vector<MapPoint> points;
  points.reserve(state.num_landmarks());
  for (int i = 0; i < state.num_landmarks(); ++i) {
    points.push_back({state.id(i), state.p_w(i), info.at(state.id(i)).observations});
  }
  return points;
}

void FinishEkfFrame(const EkfState& state, int64_t t_ns, EstimatorOutput* out,
                    Trajectory* trajectory) {
  out->T_w_c = state.T_w_c();
  out->landmarks_in_state = state.num_landmarks();
  trajectory->Add(t_ns, state.T_w_c());
}

}  // namespace dala
