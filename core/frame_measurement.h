#ifndef DALA_CORE_FRAME_MEASUREMENT_H_
#define DALA_CORE_FRAME_MEASUREMENT_H_

// FrameMeasurement: the one message from the frontend to every estimator (DESIGN.md). The
// frontend fills it; estimators (sliding-window BA, stereo EKF, mono EKF) read it and nothing
// else, so they are compared on identical measurements.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/geometry.h"
#include "core/types.h"

namespace dala {

// One interest point of the current frame that belongs to a track. `landmark` follows the
// physical point for as long as it is tracked (and again after a loop is recognised).
struct FeatureObservation {
  LandmarkId landmark;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // Left rectified image, pixels.
  // Std. dev. of uv (and of u_right), pixels: the EKFs' noise (the sliding window uses its
  // own, SlidingWindowEstimatorOptions::observation_sigma_px and tracking_sigma_px).
  double sigma_px = 1.0;
  // Stereo only: the right-image abscissa (same row, rectified) and the triangulated point
  // in the current left camera frame with its first-order covariance.
  std::optional<double> u_right;
  Eigen::Vector3d p_c0 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_p_c0 = Eigen::Matrix3d::Zero();
  int track_length = 1;  // Frames this landmark has been seen in, this one included.

  bool has_stereo() const { return u_right.has_value(); }
  double disparity() const { return uv.x() - *u_right; }
};

enum class TrackingStatus {
  kInitializing,  // First frame (or first after a reset): no motion yet.
  kTracking,      // Motion estimated from enough inliers.
  kLost,          // Too few matches or a degenerate motion: no motion estimate this frame; in
                  // System's stats and TrackResult also a frame the estimator could not place.
};
const char* TrackingStatusName(TrackingStatus status);

// The visual motion estimate between the previous processed frame and this one.
struct MotionEstimate {
  // T_prev_cur maps points of the current left camera frame into the previous one.
  Pose T_prev_cur = Pose::Identity();
  // Covariance of delta in T_prev_cur = T_hat * Exp(delta), delta = [rotation; translation].
  Matrix6d cov = Matrix6d::Identity();
  int inliers = 0;
  int correspondences = 0;
  // Monocular motion (essential matrix): the translation is a unit direction, scale unknown.
  bool scale_known = true;
};

// Time spent in each frontend stage for this frame, milliseconds.
struct FrontendTimings {
  double detect_ms = 0, stereo_ms = 0, track_ms = 0, motion_ms = 0, total_ms = 0;
  double loop_ms = 0;  // Place recognition (keyframes only).
};

// A place recognised by the frontend at this keyframe: an old keyframe seen again, verified by
// the robust matcher and a RANSAC PnP on the old keyframe's stereo points. On detection the
// frontend also relabels the current observations matched to the old keyframe's points with the
// OLD landmark ids (FeatureObservation::landmark), and the tracks continue under those ids, so an
// estimator that still holds the old landmarks (the EKF) re-observes them: that is its loop
// closing. A smoother uses T_old_cur as a loop edge of its pose graph.
struct LoopDetection {
  FrameId old_frame;  // The old keyframe's frame.
  // The current left camera in the old keyframe's left camera: p_old = T_old_cur * p_cur.
  Pose T_old_cur = Pose::Identity();
  // Covariance of delta in T_old_cur = T_hat * Exp(delta), delta = [rotation; translation].
  Matrix6d cov = Matrix6d::Identity();
  int inliers = 0;          // PnP inliers.
  int correspondences = 0;  // Verified matches before PnP.
  double appearance_score = 0.0;  // Of the place-recognition candidate (higher = more similar).
  // (current landmark id before relabelling, old landmark id) of every PnP inlier.
  std::vector<std::pair<LandmarkId, LandmarkId>> relabelled;
};

struct FrameMeasurement {
  FrameId frame;
  int64_t t_ns = 0;
  bool stereo = false;
  TrackingStatus status = TrackingStatus::kInitializing;
  std::vector<FeatureObservation> observations;
  std::optional<MotionEstimate> motion;  // Absent on the first frame and when lost.
  // Motion from a motion sensor (wheel odometry, or the rendered sequences' noisy odometry)
  // between the previous frame and this one, when the dataset has one. The System fills it;
  // the monocular EKF uses it to fix the scale.
  std::optional<MotionEstimate> odometry;
  bool is_keyframe = false;
  // Set on a keyframe where a loop was recognised (see LoopDetection).
  std::optional<LoopDetection> loop;
  // Set on a keyframe whose place an older keyframe's place-recognition entry already holds
  // (PlaceRecognitionOptions::one_entry_per_place): that keyframe's frame. The keyframe stores no
  // entry; an estimator may cull it once it has done its part (SlidingWindowEstimator). When the
  // holder is this keyframe's loop and the estimator does not close it, the place is not held
  // after all (PlaceReleasedByRefusedLoop).
  std::optional<FrameId> place_held_by;
  // Frames since the last keyframe and this frame's tracked fraction of that keyframe's points.
  double tracked_fraction = 1.0;
  FrontendTimings timings;
};

// The keyframe's place was given to the old keyframe by its loop (place_held_by), the loop
// relabelled points, and the estimator did not close it (EstimatorOutput::loop_refused): the
// place is the keyframe's own after all. The frontend stores its entry (Frontend::ReturnLoopIds),
// the System records it for the saved map, the estimator does not cull it into the old keyframe.
// (A loop that relabelled nothing found the old landmarks already tracked: that place is held.)
inline bool PlaceReleasedByRefusedLoop(const FrameMeasurement& m, bool loop_refused) {
  return loop_refused && m.loop && !m.loop->relabelled.empty() &&
         m.place_held_by == m.loop->old_frame;
}

// The loop's relabelling undone: each old landmark id it gave -> the id the point had before.
std::unordered_map<LandmarkId, LandmarkId> IdsBeforeLoop(const LoopDetection& loop);

// m with the points its loop relabelled under the ids they had before the loop (the current
// map's landmarks): what the frame observes if the loop is not closed. m itself without a loop.
FrameMeasurement WithIdsBeforeLoop(const FrameMeasurement& m);

}  // namespace dala

#endif  // DALA_CORE_FRAME_MEASUREMENT_H_
