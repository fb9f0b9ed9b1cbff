#ifndef DALA_FRONTEND_LOCAL_MAP_SEARCH_H_
#define DALA_FRONTEND_LOCAL_MAP_SEARCH_H_

// Guided search of the estimator's local map in the current image (ORB-SLAM's "track the local
// map"): the landmarks the estimator currently estimates are projected into the current frame
// from a predicted pose, and the robust matcher looks for each one's last appearance (the patch
// descriptor of the last frame that observed it) within `radius_px` of its projection. A current
// point that got no landmark id from the frame-to-frame tracking or the keyframe
// re-acquisition takes the id of the landmark it matches, so a physical point keeps ONE id even
// when its track broke for a few frames (occlusion, a missed detection, a point that moved too
// far for the constant-velocity prediction): the estimator sees long tracks instead of many
// short ones, which is what holds a monocular map's scale.
//
// The frontend still knows no estimator (DESIGN.md): the System hands it a LocalMap, a plain
// list of world points with the pose of the frame they were estimated at, after each frame.
//
// Prediction of the current camera: T_w_cur = T_w_prev * V, with T_w_prev the estimator's pose
// of the previous frame and V the velocity of the estimator's last two poses; when the frontend
// estimated this frame's visual motion, its rotation replaces V's (and, with stereo, its metric
// translation too). Descriptors are kept per landmark id for the frames that observed it, and
// forgotten when a landmark is neither in the local map nor seen for `forget_after_frames`.
//
// Not thread-safe; deterministic (ordered containers).

#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"
#include "core/geometry.h"
#include "core/types.h"
#include "frontend/harris.h"
#include "frontend/matcher.h"
#include "frontend/stereo.h"

namespace dala {

// What the System hands the frontend after each frame: the estimator's current landmarks and
// the frame's estimated pose.
struct LocalMap {
  FrameId frame;                   // The frame the estimate belongs to.
  Pose T_w_c = Pose::Identity();   // Its estimated pose (a guess when !tracked).
  bool tracked = true;             // false: the estimator lost that frame.
  std::vector<std::pair<LandmarkId, Eigen::Vector3d>> points;  // p_w.
};

struct LocalMapSearchOptions {
  bool enable = true;
  // Stereo runs turn it on by themselves while the frame-to-frame tracks break: when the mean
  // fraction of a frame's points that continue a track (exponential mean over ~5 frames, before
  // the search) falls below this; off again above it + 0.1. The tracks break when the camera
  // moves far between frames for its scene (KITTI's car: median 0.46; the rendered `fast`:
  // 0.43), which is where the search re-finds them; the slow rendered presets keep 0.70-0.80
  // (docs/results.md). 0: never; 1: from the first tracked frame on.
  double stereo_when_tracked_below = 0.55;
  double radius_px = 15.0;       // Search radius around each projection.
  // Descriptors of landmarks unseen that long (and not mapped). One camera only: a stereo
  // landmark enters the map at a frame that observes it (its appearance is then that frame's),
  // so a stereo rig forgets an unmapped appearance after one frame, with the same result.
  int forget_after_frames = 30;

  bool IsValid(std::string* why) const;
};

class LocalMapSearch {
 public:
  // `stereo`: the frames come from a stereo rig (see forget_after_frames).
  LocalMapSearch(const PinholeCamera& camera, const LocalMapSearchOptions& options,
                 const MatcherOptions& matcher, bool stereo);

  // The estimator's map after frame `map.frame` (replaces the previous one).
  void SetLocalMap(LocalMap map);

  // Assigns landmark ids to the points of `cur` (detections of frame `frame`) that have none
  // (landmark[i] invalid) and match a local-map landmark not yet present in `landmark`.
  // `previous_frame` is the frame processed before this one, `T_prev_cur` its visual motion when
  // estimated (`metric`: with its scale). Returns the number of points given an id.
  int Search(FrameId previous_frame, const std::optional<Pose>& T_prev_cur, bool metric,
             const DetectedImage& cur, std::vector<LandmarkId>* landmark,
             std::vector<int>* track_length) const;

  // Mono prediction of the frame-to-frame tracking: the points of the previous frame
  // (`previous_frame`, its detections' landmark ids `landmark`) placed in its camera by the
  // estimator's map: a mapped landmark at its estimate, any other point on its ray at the median
  // depth of the mapped ones (a scene-depth guess, so that forward motion is predicted too); and
  // the estimator's velocity T_prev_cur, in the map's unit. nullopt without a map of that frame
  // or with fewer than min_points mapped points in view.
  struct Prediction {
    Pose T_prev_cur = Pose::Identity();
    std::vector<std::optional<Eigen::Vector3d>> p_prev;  // Previous camera frame.
    std::vector<bool> mapped;  // Per point: placed at its landmark's estimate.
    int num_mapped = 0;        // Points placed at their landmark's estimate.
  };
  std::optional<Prediction> PredictFromMap(FrameId previous_frame,
                                           const std::vector<LandmarkId>& landmark,
                                           const DetectedImage& previous,
                                           int min_points = 8) const;

  // One camera's stand-in for stereo points in place recognition (frontend/place_recognition.h):
  // the current frame's points whose landmark (`landmark`, the current detections' ids) the
  // map holds, in the current camera at the predicted pose (the estimator's previous pose and
  // velocity, the visual motion's rotation when given; no covariance), with that pose and the
  // estimator's path length (map units). nullopt without a map of the previous frame or when
  // the estimator lost it.
  struct MappedPoints {
    Pose T_w_c = Pose::Identity();
    double path_length = 0.0;
    std::vector<std::optional<StereoPoint>> points;  // One per detection.
  };
  std::optional<MappedPoints> MappedPointsInCamera(FrameId previous_frame,
                                                   const std::optional<Pose>& T_prev_cur,
                                                   const std::vector<LandmarkId>& landmark) const;

  bool has_map() const { return options_.enable && map_.has_value(); }
  // The estimator lost frame `frame` (its map came with tracked = false).
  bool LostAt(FrameId frame) const { return map_ && map_->frame == frame && !map_->tracked; }
  // The estimator's pose of frame `frame` when it tracked that frame (its last local map).
  std::optional<Pose> TrackedPoseAt(FrameId frame) const {
    if (map_ && map_->frame == frame && map_->tracked) return map_->T_w_c;
    return std::nullopt;
  }
  // The landmark is in the last local map.
  bool IsMapped(LandmarkId id) const { return point_of_.count(id) > 0; }

  // Remembers the appearance of every point of frame `frame` that has a landmark id.
  void Remember(FrameId frame, const DetectedImage& detection,
                const std::vector<LandmarkId>& landmark, const std::vector<int>& track_length);
  // The points of frame `frame` (the last remembered) that had id `old` take the id `now`
  // (old -> now in `rename`: a loop's relabelling the estimator did not use): the appearance
  // frame `frame` gave `old` becomes `now`'s; `old` keeps none unless the map holds it.
  void RenameRemembered(FrameId frame, const std::unordered_map<LandmarkId, LandmarkId>& rename);

 private:
  struct Appearance {
    InterestPoint point;
    std::vector<float> descriptor;
    int track_length = 1;
    int64_t last_seen = 0;  // Frame id value.
  };

  // The current pose predicted from the map's (see the file comment); needs a map.
  Pose PredictPose(const std::optional<Pose>& T_prev_cur, bool metric) const;

  PinholeCamera camera_;
  LocalMapSearchOptions options_;
  MatcherOptions matcher_;
  int forget_after_frames_;  // options_'s, or 1 for a stereo rig.
  std::optional<LocalMap> map_;
  std::unordered_map<LandmarkId, Eigen::Vector3d> point_of_;  // map_'s points by id.
  Pose velocity_ = Pose::Identity();  // T_prev_cur of the estimator's last two poses.
  std::optional<std::pair<FrameId, Pose>> previous_estimate_;
  double path_length_ = 0.0;  // Of the estimator's tracked poses, map units.
  std::map<LandmarkId, Appearance> appearance_;
};

}  // namespace dala

#endif  // DALA_FRONTEND_LOCAL_MAP_SEARCH_H_
