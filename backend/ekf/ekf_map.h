#ifndef DALA_BACKEND_EKF_EKF_MAP_H_
#define DALA_BACKEND_EKF_EKF_MAP_H_

// Map management shared by StereoEkfEstimator and MonoEkfEstimator: the bookkeeping of each state
// landmark, the image grid that spreads landmarks over the view (paper: 4x4 zones), the eviction
// order of a full state, and the map() / EstimatorOutput of a frame.
//
// Eviction rule (the state is bounded; the paper keeps landmarks that left the view, since they
// are what a loop re-observes): only landmarks unseen for at least `min_unseen_frames` may go;
// among them, those with the fewest applied observations first (short-lived tracks are the least
// reliable and the least likely to be recognised again), then the most recently created first
// (the oldest landmarks are the ones that correct the most drift when a loop re-observes them).

#include <Eigen/Core>
#include <unordered_map>
#include <vector>

#include "backend/ekf/ekf_state.h"
#include "backend/estimator.h"
#include "core/trajectory.h"
#include "core/types.h"

namespace dala {

struct EkfLandmarkInfo {
  int created = 0;        // Frame index of its initialisation.
  int last_seen = 0;      // Frame index of the last applied observation.
  int observations = 0;   // Applied observations (the initialisation included).
  int gate_failures = 0;  // Consecutive.
};
using EkfLandmarkInfoMap = std::unordered_map<LandmarkId, EkfLandmarkInfo>;

// cols x rows zones over a width x height image; zones are numbered row-major.
class ImageGrid {
 public:
  ImageGrid(int width, int height, int cols, int rows);
  int size() const { return cols_ * rows_; }
  // The zone of a pixel (clamped into the image).
  int Zone(const Eigen::Vector2d& uv) const;

 private:
  double width_, height_;
  int cols_, rows_;
};

// State indices of the landmarks that may be evicted, in eviction order (file comment).
std::vector<int> EvictionOrder(const EkfState& state, const EkfLandmarkInfoMap& info, int frame,
                               int min_unseen_frames);

// The state's landmarks as MapPoints (observations from `info`).
std::vector<MapPoint> EkfMapPoints(const EkfState& state, const EkfLandmarkInfoMap& info);

// Fills the pose and state size of `out` and appends the pose to the trajectory.
void FinishEkfFrame(const EkfState& state, int64_t t_ns, EstimatorOutput* out,
                    Trajectory* trajectory);

}  // namespace dala

#endif  // DALA_BACKEND_EKF_EKF_MAP_H_
