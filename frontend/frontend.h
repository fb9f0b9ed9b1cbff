#ifndef DALA_FRONTEND_FRONTEND_H_
#define DALA_FRONTEND_FRONTEND_H_

// The visual frontend: for each frame, interest points, stereo, tracking (to the previous frame
// and to the last keyframe), visual motion and the keyframe decision, packed into the
// FrameMeasurement that every estimator consumes (core/frame_measurement.h). It knows no
// estimator.
//
// Tracking: the previous frame's points are predicted in the current image with a constant-
// velocity motion (points with depth are reprojected, points without depth are rotated), the
// matcher searches around the predictions, and the motion estimator keeps the inliers. If that
// fails (a jerk), matching is retried without a prior, as for a loop closure. A current point
// inherits the landmark id of its previous-frame match when that match is an inlier of the
// motion (or, without depth, when it lies within `epipolar_gate_px` of its epipolar line);
// points without an inherited id are matched to the last keyframe (re-acquiring landmarks
// lost for a few frames), then to the estimator's local map when the System gave one
// (frontend/local_map_search.h), and the rest start new landmarks.
//
// Loop detection (stereo, options.loop.enable): every keyframe is searched for in the keyframe
// database (frontend/place_recognition.h) and then added to it. On a verified loop the
// measurement carries a LoopDetection, and the current points matched to the old keyframe's
// points (PnP inliers) take the OLD landmark ids; the tracks continue under those ids.
//
// Usage:
//   dala::Frontend frontend(dataset->rig(), dala::FrontendOptions());
//   dala::Frame frame;
//   while (dataset->Next(&frame)) {
//     const dala::FrameMeasurement m = frontend.Process(frame);
//     estimator.Add(m);
//   }
// Not thread safe (one frontend per sequence); the same frames and options give the same output.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/frame_measurement.h"
#include "core/types.h"
#include "frontend/harris.h"
#include "frontend/keyframe_policy.h"
#include "frontend/local_map_search.h"
#include "frontend/matcher.h"
#include "frontend/motion_estimator.h"
#include "frontend/place_recognition.h"
#include "frontend/stereo.h"
#include "frontend/worker_thread.h"

namespace dala {

// Detector settings for sequences: two pyramid levels (frame-to-frame scale changes are small)
// and a bounded number of points, which keeps matching and estimation within a frame budget.
HarrisOptions SequenceHarrisOptions();

struct FrontendOptions {
  HarrisOptions harris = SequenceHarrisOptions();
  StereoOptions stereo;
  MatcherOptions tracking_matcher = MatcherOptions::ForTracking();
  MotionEstimatorOptions motion;
  KeyframePolicyOptions keyframe;
  // Search radius around the constant-velocity prediction, pixels.
  double tracking_radius_px = 30.0;
  // One camera before the map exists: when the matches around the prediction keep fewer than
  // this fraction of the previous frame's points as motion inliers, the frame is also matched
  // without a prior and the attempt with more inliers kept (fast forward motion; see
  // Frontend::TrackFromPrevious). KITTI 06 at 10 Hz keeps 17.8-40 % (starts 0..9), every 2nd / 3rd
  // frame of it 14-19 % / 10-14 %. 0: never.
  double mono_free_matching_below = 0.15;
  // One camera while the estimator's two-view initialisation waits (SetEstimatorInitializing):
  // match a frame again around its estimated rotation when that differs from the constant
  // rotation rate's prediction by more than half tracking_radius_px (a change of yaw rate), and
  // keep the matching with more inliers. Measured, not the default (docs/results.md, "stop 58").
  bool mono_init_rematch = false;
  // Matches of points without depth must lie this close to their epipolar line (pixels).
  double epipolar_gate_px = 2.0;
  // Reprojection gate for the re-acquisition of lost landmarks from the last keyframe (pixels).
  double keyframe_gate_px = 3.0;
  // Use a second thread: the right image is detected, and the temporal matches of the first
  // tracking attempt are made, beside the left detection and the stereo matching (does not
  // change the result).
  bool parallel_detection = true;
  // Loop detection at keyframes (stereo): place recognition + relabelling of the recognised
  // landmarks with their old ids (frontend/place_recognition.h).
  PlaceRecognitionOptions loop;
  // Guided search of the estimator's local map (frontend/local_map_search.h), when the System
  // hands one over (SetLocalMap).
  LocalMapSearchOptions local_map;

  bool IsValid(std::string* why) const;
};

// Throws dala::Error naming the frame, the image and the fix when the caller's frame cannot be
// processed with `rig`: an empty or non-8-bit-grey left image, a left or right image whose size
// is not the calibration's. (A right image on a monocular rig is ignored, not an error.)
void CheckFrameSuitsRig(const Frame& frame, const StereoRig& rig);

// What the frontend computes from a frame's images alone: the left image's interest points and,
// for a stereo frame, each one's stereo match. It depends on the images, the rig and the options
// `harris` and `stereo`, never on earlier frames or on a RANSAC, so pipelines over the same
// frames that differ in their RANSAC draws compute it once (SystemEnsemble) and each gets the
// result it would have computed itself.
struct FrameFeatures {
  FrameId frame;
  bool stereo = false;  // The frame was matched in stereo (a stereo rig and a right image).
  DetectedImage left;
  std::vector<std::optional<StereoPoint>> stereo_points;  // Per left point; stereo frames.
  double detect_ms = 0.0, stereo_ms = 0.0;                // The time it took, per step.
};

// Computes a frame's features as Frontend::Process would: `helper` (optional; used only with
// options.parallel_detection) detects the right image beside the left one, or helps with the
// left image's pyramid levels for one camera. Throws as CheckFrameSuitsRig does.
FrameFeatures ComputeFrameFeatures(const Frame& frame, const StereoRig& rig,
                                   const FrontendOptions& options, WorkerThread* helper);

class Frontend {
 public:
  Frontend(const StereoRig& rig, const FrontendOptions& options);

  // Processes the next frame (frames in time order). Images must be CV_8UC1 and of the rig's
  // size: CheckFrameSuitsRig throws dala::Error otherwise, before anything changes.
  FrameMeasurement Process(const Frame& frame);
  // The same, with the frame's features computed already (ComputeFrameFeatures with this
  // frontend's rig and options): the same measurement, without detecting the images again; its
  // timings count the features' time. Throws dala::Error, before anything changes, for
  // features of another frame or image size. Features computed with other Harris or stereo
  // options are the caller's mistake, not detected.
  FrameMeasurement Process(const Frame& frame, const FrameFeatures& features);

  // Pose of the current camera obtained by chaining the visual motion estimates from the first
  // frame (identity): visual odometry, drifting like any dead reckoning. When tracking is lost
  // for a frame, the last velocity is assumed for it.
  const Pose& dead_reckoning_T_w_c() const { return T_w_cur_; }

  const StereoRig& rig() const { return rig_; }
  // The estimator's landmarks after the frame just processed (see local_map_search.h): the next
  // frame searches them around their predicted projections.
  void SetLocalMap(LocalMap map) { local_map_search_.SetLocalMap(std::move(map)); }
  // Whether the estimator's last frame was still waiting for its first map (its two-view
  // initialisation; EstimatorOutput::initializing). True until told otherwise.
  void SetEstimatorInitializing(bool initializing) { estimator_initializing_ = initializing; }
  // Starts the run in a saved map (System::UseMap, before the first frame): its keyframes join
  // the place recognition for relocalisation, the new landmark ids start after the map's, and
  // every frame is relocalised against the database until the estimator reports one tracked
  // (SetLocalMap). The map must suit the options (System::UseMap checks it).
  void UseMap(const SavedMap& map);
  // The estimator left the observations a loop relabelled unused (it did not close the loop:
  // EstimatorOutput::loop_refused): the frame just processed gives those points back the ids
  // they had before the loop, in what the next frames track from, in the appearances the
  // local-map search keeps and in its place-recognition entry, so that their tracks go on in the
  // current map instead of ending in old ids the estimator ignores. A keyframe whose place the
  // refused loop had given to the old keyframe (FrameMeasurement::place_held_by) holds its own
  // place again: its entry joins the database. The next keyframe searches for a loop again
  // (PlaceRecognition::LoopNotClosed). Call it after Process, before the next frame.
  void ReturnLoopIds(const LoopDetection& loop);
  // The keyframe database and the last search's statistics.
  const PlaceRecognition& place_recognition() const { return place_recognition_; }
  PlaceRecognition* mutable_place_recognition() { return &place_recognition_; }

  // The current keyframe (the last frame whose measurement had is_keyframe): its interest points
  // with their patch descriptors, and each point's landmark id (invalid: none). Null before the
  // first keyframe. What a saved map keeps of a keyframe (System::SaveMap).
  const DetectedImage* keyframe_detection() const {
    return keyframe_ ? &keyframe_->detection : nullptr;
  }
  const std::vector<LandmarkId>* keyframe_landmarks() const {
    return keyframe_ ? &keyframe_->landmark : nullptr;
  }

 private:
  // What is kept of a processed frame for the next ones.
  struct TrackedFrame {
    FrameId id;
    DetectedImage detection;
    std::vector<LandmarkId> landmark;  // Per point; invalid when the point has none yet.
    std::vector<int> track_length;
    std::vector<std::optional<StereoPoint>> stereo;
    Pose T_w_c = Pose::Identity();  // Dead-reckoned pose.
  };

  // Process, with the frame's features when they were computed already.
  FrameMeasurement ProcessFrame(const Frame& frame, const FrameFeatures* features);
  // Process's steps, in order.
  // Takes over what the estimator said of the previous frame (its pose after a relocalisation,
  // the last keyframe it tracked).
  void FollowEstimator();
  // Detects the left image into *cur (its landmarks unset) and returns the right image's points.
  DetectedImage Detect(const Frame& frame, bool stereo, TrackedFrame* cur);
  // Every point of *cur without a landmark yet, its track one frame long.
  void StartTracks(TrackedFrame* cur);
  // Whether the first tracking attempt's temporal matches are made on the worker beside the
  // stereo matching (MatchStereoAndPredict).
  bool PredictsBesideStereo(bool stereo) const;
  // The same from features computed already: *cur gets their left points (with a cache of its
  // own) and stereo matches, and the temporal matches are predicted as
  // MatchStereoAndPredict would (returned).
  std::optional<std::vector<Match>> AdoptFeatures(const FrameFeatures& features, TrackedFrame* cur);

  // The stereo points of *cur, and beside them (on the worker) the temporal matches predicted
  // by the constant velocity, which TrackFromPrevious tries first.
  std::optional<std::vector<Match>> MatchStereoAndPredict(const Frame& frame, bool stereo,
                                                          const DetectedImage& right,
                                                          TrackedFrame* cur);
  // Tracks from the previous frame and dead-reckons cur->T_w_c (the last velocity when lost).
  std::optional<MotionEstimate> TrackAndDeadReckon(
      TrackedFrame* cur, std::optional<std::vector<Match>> predicted_matches,
      TrackingStatus* status);
  // Whether the guided local-map search runs for this frame: one camera always; stereo while
  // the mean fraction of continued tracks stays below local_map.stereo_when_tracked_below.
  bool GuidedSearchOn(FrameId frame, bool stereo, bool tracked, const TrackedFrame& cur);
  // Gives every point of *cur its landmark (re-acquired, found in the local map, relocalised,
  // or new); true when the frame was relocalised from the database.
  bool FindLandmarks(const Frame& frame, const std::optional<MotionEstimate>& motion,
                     bool guided, bool lost_before, TrackedFrame* cur);
  // The keyframe decision (out->tracked_fraction is set from its evidence).
  bool DecideKeyframe(const TrackedFrame& cur, bool stereo, bool guided, bool relocalised,
                      FrameMeasurement* out);
  void FillObservations(const TrackedFrame& cur, FrameMeasurement* out) const;

  // Matches prev -> cur around the predicted positions; empty prediction = no prior.
  // `p_from`: the points of `from` in its camera when known (default: its stereo points).
  std::vector<Match> MatchTemporal(
      const TrackedFrame& from, const DetectedImage& cur, const Pose* T_from_cur,
      const std::vector<std::optional<Eigen::Vector3d>>* p_from = nullptr) const;
  // Inherits ids from `prev` through the motion inliers; returns the motion, if any.
  // `predicted_matches`: the first attempt's MatchTemporal result when already computed.
  std::optional<MotionEstimate> TrackFromPrevious(
      TrackedFrame* cur, std::optional<std::vector<Match>> predicted_matches = std::nullopt);
  void ReacquireFromKeyframe(TrackedFrame* cur) const;
  // After a frame the estimator lost (one camera): the keyframe's mapped landmarks matched
  // without a prior (frontend/local_map_search.h).
  void RelocalizeFromKeyframe(TrackedFrame* cur) const;
  // After a frame the estimator lost, when the place recognition keeps a database: the current
  // place searched among ALL keyframes (PlaceRecognition::Relocalize); the recognised points
  // that carry no mapped id take the old landmark ids, which the estimator verifies by PnP.
  // True when a place was recognised.
  bool RelocalizeFromDatabase(const Frame& frame, TrackedFrame* cur);
  // At a keyframe: searches the database, relabels the recognised points, adds the keyframe
  // unless an older entry holds its place (then *held_by: that entry's frame).
  std::optional<LoopDetection> DetectLoop(const Frame& frame,
                                          const std::optional<MotionEstimate>& motion,
                                          TrackedFrame* cur, std::optional<FrameId>* held_by);

  StereoRig rig_;
  FrontendOptions options_;
  MotionEstimator motion_estimator_;
  KeyframePolicy keyframe_policy_;
  PlaceRecognition place_recognition_;
  LocalMapSearch local_map_search_;
  bool estimator_initializing_ = true;  // See SetEstimatorInitializing.
  WorkerThread detection_worker_;  // Detects the right image (persistent: keeps its scratch).
  std::optional<TrackedFrame> prev_;
  std::optional<TrackedFrame> keyframe_;
  std::optional<TrackedFrame> tracked_keyframe_;  // The last keyframe the estimator tracked.
  Pose velocity_T_prev_cur_ = Pose::Identity();
  double mono_step_length_ = 1.0;  // One camera: the last non-zero dead-reckoned step (no unit).
  Pose T_w_cur_ = Pose::Identity();
  double path_length_m_ = 0.0;  // Dead-reckoned distance travelled.
  int64_t next_landmark_ = 0;
  int frames_since_keyframe_ = 0;
  // The older entry that holds the last keyframe's place, if any, and the keyframe's own entry,
  // left out of the database for it (DetectLoop). ReturnLoopIds stores that entry after all
  // when the holder was a loop the estimator refused.
  std::optional<FrameId> keyframe_held_by_;
  std::optional<KeyframeEntry> keyframe_unstored_entry_;
  // A frame was relocalised from the database: once the estimator has placed a frame, the
  // stereo dead reckoning continues from the estimator's pose instead of the extrapolation of
  // the gap.
  bool relocalised_prev_ = false;
  // Stereo: the exponential mean of the fraction of points continuing a track, and whether the
  // guided search is on because of it (LocalMapSearchOptions::stereo_when_tracked_below);
  // -1 before the first tracked frame.
  double mean_tracked_fraction_ = -1.0;
  bool stereo_search_on_ = false;
  // UseMap: no frame tracked in the saved map yet.
  bool awaiting_map_ = false;
};

}  // namespace dala

#endif  // DALA_FRONTEND_FRONTEND_H_
