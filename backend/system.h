#ifndef DALA_BACKEND_SYSTEM_H_
#define DALA_BACKEND_SYSTEM_H_

// dala::System: the pipeline. It owns a Frontend and an Estimator and wires them (DESIGN.md),
// keeps per-frame statistics, and gives the trajectory of every frame and the map.
//
//   auto dataset = dala::OpenDataset("kitti/sequences/06");
//   dala::System system(dataset->rig(), dala::SystemOptions());
//   dala::Frame frame;
//   while (dataset->Next(&frame)) {
//     const dala::TrackResult r = system.Track(frame);   // r.status, r.T_w_c
//   }
//   dala::WriteTrajectoryTum("trajectory.txt", system.trajectory());
//
// The world frame is the first frame's left camera. Not thread-safe; deterministic.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "backend/estimator.h"
#include "backend/system_options.h"
#include "core/camera.h"
#include "core/io/map_file.h"
#include "frontend/frontend.h"

namespace dala {

struct TrackResult {
  TrackingStatus status = TrackingStatus::kInitializing;
  // The frame's pose as estimated when Track returns. With the BA estimator's window solve in
  // the background (ba.background_solve, default), a keyframe's pose is the one before its
  // window solve; trajectory() gives every pose as later optimisation corrected it.
  Pose T_w_c = Pose::Identity();
  // The estimator estimated this frame (false: extrapolated, or no pose at all while a mono
  // estimator initialises: status kInitializing).
  bool valid = false;
  bool keyframe = false;
};

// What the run report records of each frame.
struct FrameStats {
  FrameId frame;
  int64_t t_ns = 0;
  TrackingStatus status = TrackingStatus::kInitializing;
  bool valid = false;
  bool skipped = false;  // Its images could not be read (SkipFrame): lost, no pose.
  bool keyframe = false;
  int places = 0;  // Place-recognition entries after this frame (System::places()).
  // Keyframes in the estimator's map after this frame (EstimatorOutput::keyframes_in_map: made
  // minus culled; -1 for an estimator that keeps none).
  int keyframes_in_map = -1;
  std::optional<double> disparity_offset_px;  // EstimatorOutput::disparity_offset_px.
  int features = 0;
  int tracked = 0;           // Observations continuing a track.
  int landmarks = 0;         // In the estimator's state.
  bool loop = false;         // The frontend recognised a place (measurement.loop).
  bool loop_closed = false;  // The estimator corrected the trajectory with it.
  // The old keyframe's frame of the place recognised (measurement.loop->old_frame), when loop.
  std::optional<FrameId> loop_old_frame;
  std::string loop_not_closed;  // EstimatorOutput::loop_not_closed.
  std::string note;  // The estimator's word on this frame ("initialising: <reason>"), if any.
  FrontendTimings frontend;
  double estimator_ms = 0;
  double total_ms = 0;
};

// Makes the estimator named by options.estimator/mode. Throws dala::Error for a combination
// that does not exist (e.g. "ba" + "mono"), saying which do.
std::unique_ptr<Estimator> MakeEstimator(const StereoRig& rig, const SystemOptions& options);

// Whether a ScaleDescription() (report.json's summary.scale_source) says the unit is the metre:
// it starts with "metric".
bool IsMetricScale(const std::string& scale_description);

class System {
 public:
  // Throws dala::Error when the options are invalid or the rig does not suit the mode
  // (stereo mode on a monocular dataset).
  System(const StereoRig& rig, const SystemOptions& options);

  // Tracks the next frame. Throws dala::Error, with nothing changed, on the caller's mistakes: a
  // frame before the previous one in time, an image that is empty, not 8-bit grey, or not of
  // the rig's size (CheckFrameSuitsRig, frontend/frontend.h).
  TrackResult Track(const Frame& frame);
  // The same, with the frame's features computed already (ComputeFrameFeatures with rig() and
  // options().frontend): the same result, without detecting the images again. How
  // SystemEnsemble shares one detection between its draws. Throws dala::Error, with nothing
  // changed, also for features of another frame (Frontend::Process).
  TrackResult Track(const Frame& frame, const FrameFeatures& features);
  // Records a frame whose images could not be read (dala run skips such a frame): stats() report
  // it lost with `note`, and it gets no pose. Neither the frontend nor the estimator sees it: the
  // next frame is tracked from the intact frame before the gap (the constant-velocity prediction,
  // then matching without a prior, as after a jerk), and if that fails it is lost and then
  // relocalised like any lost frame.
  void SkipFrame(FrameId frame, int64_t t_ns, const std::string& note);

  // After the last frame of an offline run (`dala run` calls it): the estimator's global
  // refinement when it has one (the BA estimator: a global bundle adjustment over every
  // keyframe, backend/ba/global_ba.h, when options.ba.final_ba says so: by default for a stereo
  // rig whose disparity offset was calibrated online); trajectory(), map() and the saved map
  // then give the refined estimates.
  // Otherwise nothing changes (done = false, `report` says why). Frames may still be tracked
  // after it. stop_requested (may be empty; `dala run` passes its Ctrl-C) is polled while the
  // refinement works: once it returns true, the refinement ends and the online estimates stay.
  RefinementSummary Finish(const std::function<bool()>& stop_requested = nullptr);

  // Every frame tracked so far that has a pose (estimates corrected by later optimisation);
  // a mono run leaves out the frames before its initialisation (stats() says which).
  Trajectory trajectory() const { return estimator_->trajectory(); }
  std::vector<MapPoint> map() const { return estimator_->map(); }
  // Every keyframe so far (the frames the frontend chose) but those whose place an older one
  // holds (PlaceRecognitionOptions::one_entry_per_place), in order, with its current pose
  // (corrected by later optimisation) and its points that belong to a landmark (older than
  // kRecordPruneAge keyframes: to a landmark of the map): position, orientation, scale and
  // patch descriptor (frontend/harris.h).
  std::vector<SavedKeyframe> keyframes() const;
  const std::vector<FrameStats>& stats() const { return stats_; }
  // The frontend's measurement of the last frame tracked (empty before the first): what it
  // detected, tracked and matched in stereo (`dala run --video` draws it). A skipped frame
  // leaves it as it was.
  const FrameMeasurement& last_measurement() const { return last_measurement_; }
  // Places the place recognition stores (one per keyframe, but one per place on revisits).
  size_t places() const { return frontend_->place_recognition().database().size(); }

  // Writes the map: keyframes (poses, points, descriptors) and landmarks (core/io/map_file.h
  // gives the versioned binary format). Throws dala::Error when the file cannot be written.
  void SaveMap(const std::string& path) const;
  // Reads a map written by SaveMap (dala::Error on a missing, foreign, corrupted or other-version
  // file). The map is returned for use (inspection, or UseMap to run in it).
  static SavedMap LoadMap(const std::string& path);
  // Starts this run in a saved map (call before the first Track; `dala run --map FILE`): every
  // frame is relocalised against the map's keyframes (place recognition, then PnP on its
  // landmarks) until one is placed; frames before have no pose (note "localising in the saved
  // map ..."); the run then goes on in the map's frame and unit, adding its own keyframes and
  // landmarks (SaveMap writes the run's keyframes and every landmark). Throws dala::Error when
  // the map does not suit the run (a stereo run in a one-camera map, other descriptor or
  // thumbnail sizes, relocalisation off, an estimator that cannot, a malformed map). The BA
  // estimator only.
  void UseMap(const SavedMap& map);
  const SystemOptions& options() const { return options_; }
  // The rig in use: the one given, without its right camera in mode "mono" (one camera).
  const StereoRig& rig() const { return rig_; }
  // What fixes the map's unit: "metric (stereo)", "metric (odometry)" (the mono EKF fed by the
  // dataset's odometry), "metric (stereo visual motion)" (the mono EKF fed by the stereo motion)
  // or "arbitrary (monocular)" (one camera: the unit is the first two-view baseline; align with
  // Sim(3) to compare with a metric ground truth).
  std::string ScaleDescription() const;
  // The map's unit is the metre (IsMetricScale(ScaleDescription())).
  bool IsMetric() const;
  const Estimator& estimator() const { return *estimator_; }

  // The saved keyframes (keyframes(), SaveMap) older than kRecordPruneAge keyframes keep only
  // their points whose landmark is in the estimator's map (PruneKeyframeRecords, every
  // kRecordPruneEvery keyframes and before a save).
  // Why: a point whose landmark never entered the map (a stereo point seen by one keyframe, a
  // track the BA rejected, an EKF landmark evicted) has no position in the saved map, so a run
  // relocalising in it cannot use the point (PnP needs the landmark, place recognition ranks by
  // thumbnail); on the rendered rover_loop 58 % of the recorded points are such, ~0.27 MB of
  // descriptors per keyframe. kRecordPruneAge is far beyond the window (8 keyframes), where a
  // landmark enters the map; one re-found later by a loop closure loses its old keyframe's point.
  static constexpr size_t kRecordPruneAge = 32;
  static constexpr size_t kRecordPruneEvery = 16;

 private:
  TrackResult TrackFrame(const Frame& frame, const FrameFeatures* features);
  void RecordKeyframe(const cv::Mat& left);

  StereoRig rig_;
  SystemOptions options_;
  std::unique_ptr<Frontend> frontend_;
  std::unique_ptr<Estimator> estimator_;
  std::vector<FrameStats> stats_;
  FrameMeasurement last_measurement_;
  std::optional<Pose> T_w_odom_prev_;  // The previous frame's odometry pose, if it had one.
  bool odometry_given_ = false;        // A measurement carried odometry to the estimator.
  bool local_map_handed_ = false;      // The estimator gave the frontend a local map once.
  std::optional<bool> saved_map_metric_;  // UseMap: the saved map's unit is the metre.
  // The keyframes with their points, and each one's index in the trajectory: frame, time and
  // pose are refreshed from the estimator's trajectory when asked (they follow later
  // corrections). Mutable: a cache that the const readers (keyframes(), SaveMap) bring up to
  // date; SaveMap hands them to the writer by reference (~0.5 MB of descriptors per keyframe).
  mutable std::vector<SavedKeyframe> keyframe_records_;
  mutable size_t pruned_records_ = 0;  // Records [0, pruned_records_) have been pruned.
  void PruneKeyframeRecords(const std::vector<MapPoint>& map) const;  // map: estimator_->map()
  std::vector<size_t> keyframe_trajectory_index_;
  mutable std::vector<bool> keyframe_has_pose_;  // By RefreshKeyframePoses.
  void RefreshKeyframePoses() const;
};

}  // namespace dala

#endif  // DALA_BACKEND_SYSTEM_H_
