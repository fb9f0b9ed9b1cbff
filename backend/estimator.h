#ifndef DALA_BACKEND_ESTIMATOR_H_
#define DALA_BACKEND_ESTIMATOR_H_

// The estimator interface: what the System (backend/system.h) drives. Every estimator takes the
// same FrameMeasurement stream from the frontend, so benchmarks compare estimators, not frontends.
//   SlidingWindowEstimator (backend/ba):  Ceres BA over the last keyframes + marginalisation.
//   StereoEkfEstimator (backend/ekf):     the paper's stereo EKF-SLAM.
//   MonoEkfEstimator (backend/ekf):       the paper's bearing-only EKF-SLAM (Gaussian-sum init).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/frame_measurement.h"
#include "core/geometry.h"
#include "core/trajectory.h"
#include "core/types.h"

namespace dala {

// A landmark of the estimator's map, in the world frame.
struct MapPoint {
  LandmarkId id;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  int observations = 0;
};

// What an estimator says about the frame it just consumed.
struct EstimatorOutput {
  // T_w_c0 of the frame (the world frame is the first frame's camera unless said otherwise).
  Pose T_w_c = Pose::Identity();
  // False when the estimator could not estimate this frame: T_w_c is then an extrapolation; the
  // BA estimator leaves the frame out of trajectory(), the EKFs keep the extrapolation there.
  bool valid = false;
  // A monocular estimator waiting for its two-view initialisation: the frame has no pose yet
  // (T_w_c is meaningless; it may get one later, when the map exists, and trajectory() then
  // holds it) and `note` says why ("initialising: too little parallax: ...").
  bool initializing = false;
  std::string note;
  // The landmarks the estimator holds now (world points), which the frontend searches for in
  // the next frame (frontend/local_map_search.h); empty when the estimator offers none.
  std::vector<std::pair<LandmarkId, Eigen::Vector3d>> local_map;
  int landmarks_in_state = 0;  // Landmarks currently estimated (window / filter state).
  // Keyframes the estimator's map holds now (the BA: made minus culled); -1: it keeps none.
  int keyframes_in_map = -1;
  // The stereo rig's disparity offset in use after this frame (StereoIntrinsics::
  // disparity_offset_px: calibrated or estimated online); nullopt: the estimator has none.
  std::optional<double> disparity_offset_px;
  bool loop_closed = false;    // A loop closure corrected the trajectory at this frame.
  // The frame's loop detection was not closed and the observations the frontend relabelled with
  // the old landmarks' ids are left unused (one camera: the gate refused the loop, or nothing
  // verified it); the frontend gives the points their ids back (Frontend::ReturnLoopIds).
  bool loop_refused = false;
  // Why the estimator did not close the frame's loop ("the old frame is not a keyframe of the
  // map", "it would turn the camera by ..."); empty when it closed it or judged none.
  std::string loop_not_closed;
};

// What Estimator::Refine did.
struct RefinementSummary {
  bool done = false;     // false: nothing changed (`report` says why).
  bool stopped = false;  // The caller's stop request ended it (done is then false).
  std::string report;  // One line for the log.
  int keyframes = 0;
  int landmarks = 0;
  int observations = 0;
  int outliers_removed = 0;
  double initial_cost = 0.0;  // The solver's cost before and after (0.5 sum rho(|r|^2)).
  double final_cost = 0.0;
  double time_s = 0.0;
};

class Estimator {
 public:
  virtual ~Estimator() = default;

  // "ba" or "ekf", and the mode "stereo" or "mono".
  virtual std::string name() const = 0;
  virtual std::string mode() const = 0;

  // Consumes the next frame's measurement (frames in time order).
  virtual EstimatorOutput Add(const FrameMeasurement& measurement) = 0;

  // The estimated pose of every frame consumed so far that has one, in order (with loop
  // corrections applied to the past). Frames without a pose (a monocular estimator before its
  // initialisation) are left out: match the poses to frames by time.
  virtual Trajectory trajectory() const = 0;

  // The current map.
  virtual std::vector<MapPoint> map() const = 0;

  // After the last frame of an offline run: re-estimates the whole trajectory and map at once
  // (the BA estimator: a global bundle adjustment over every keyframe, backend/ba/global_ba.h),
  // so trajectory() and map() give the refined estimates. Frames may still be added after it.
  // stop_requested (may be empty) is polled while it works (from the calling thread; with
  // several Systems refined at once, from each of theirs): once it returns true the refinement
  // ends and nothing changes (done = false, stopped = true, the report says so).
  // Default: an estimator that cannot (the EKFs: a filter has no past to revisit).
  virtual RefinementSummary Refine(const std::function<bool()>& /*stop_requested*/) {
    RefinementSummary s;
    s.report = "no global refinement for the " + name() + "/" + mode() + " estimator";
    return s;
  }

  // Starts in a saved map (before the first measurement): its landmarks (world points, ids
  // unique in the run) are the map every frame is placed in until one is (by PnP on the
  // landmarks the frontend recognised: frames before that get no pose); the run then goes on
  // in the map's frame and unit. False: this estimator cannot (the caller says so).
  virtual bool UseMap(const std::vector<MapPoint>& /*landmarks*/) { return false; }

  // One line on the stereo rig's disparity offset the estimator uses and where it comes from
  // ("0.309 px, calibrated online from 44 windows"); empty for an estimator without one.
  virtual std::string DisparityOffsetNote() const { return {}; }
  // Its value now (pixels); nullopt for an estimator without one.
  virtual std::optional<double> DisparityOffsetPx() const { return std::nullopt; }
};

}  // namespace dala

#endif  // DALA_BACKEND_ESTIMATOR_H_
