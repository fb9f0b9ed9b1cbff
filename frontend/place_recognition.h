#ifndef DALA_FRONTEND_PLACE_RECOGNITION_H_
#define DALA_FRONTEND_PLACE_RECOGNITION_H_

// Place recognition for loop closure: at each keyframe, is this a place seen long ago?
//
// 1. Candidates by appearance. The global descriptor is a small thumbnail of the left image
//    (area-averaged to thumbnail_width x thumbnail_height, z-normalised); two keyframes score
//    the best ZNCC of their thumbnails over small shifts (+-max_shift_x/y thumbnail pixels, i.e.
//    a few degrees of yaw/pitch). 16x10 separated revisits from other places best among 64x40,
//    40x24, 32x20, 20x12 and 16x10 on the small loop (finer thumbnails decorrelate within 0.5 m
//    of forward motion: the near walls and ground dominate them). Why a thumbnail rather than a vocabulary over our point
//    descriptors: it needs no training data (a bag of words over 11x11 patches would need a
//    vocabulary learnt on representative images, and our patches are rotation-normalised, so
//    they carry little of what distinguishes one place from another), it costs ~1 us per
//    comparison, and a rover revisiting a place follows nearly the same viewpoint, which is
//    the case a thumbnail handles well. The robust matcher (which is viewpoint tolerant) and the
//    PnP do the real verification; the thumbnail only ranks.
//    Excluded: keyframes less than min_frame_gap frames old; with a stereo rig, keyframes
//    fewer than 2 x gate_radius_m metres back along the dead-reckoned path (the camera cannot
//    have left their gate and come back: their view is the current map's); and (spatial
//    gate, the known
//    implementation of the paper's loop closing looked within 3 m of the estimate) keyframes
//    whose dead-reckoned position is farther from the current one than
//      gate_radius_m + gate_fraction * (dead-reckoned path length between the two keyframes),
//    i.e. farther than the visual odometry can have drifted. Without this gate a place that
//    looks identical but is elsewhere (the `false_loop` preset) cannot be told apart by images.
// 2. Verification of the top_k candidates (best first, score >= min_appearance_score): the
//    robust matcher without prior (any rotation, scale), old keyframe's stereo points -> current
//    points, then a seeded RANSAC PnP (frontend/motion_estimator.h) on the old keyframe's stereo
//    points in its camera against the current (u, v[, d]). One camera: the keyframe keeps its
//    points with a landmark id (no depth), the matches are verified by the essential matrix or,
//    when the viewpoints nearly coincide (degenerate epipolar geometry), by a rotation's
//    homography, whichever keeps more; the estimator then checks them in 3D (the similarity
//    of the recognised landmarks' two estimates, backend/mono/loop_sim3.h), and there is no
//    PnP pose to gate. Accepted with >= min_inliers inliers, inliers / matches >=
//    min_inlier_ratio, and (stereo) the PnP's implied current pose T_w_old * T_old_cur within
//    the spatial gate of the dead-reckoned one: its position as above, and its orientation
//    within gate_rotation_deg + gate_rotation_deg_per_m x (path between the keyframes).
//
// Deterministic (seeded RANSAC, ordered scans, ties broken by frame id).
//
// Usage (the Frontend does this at each keyframe):
//   PlaceRecognition pr(rig, options);
//   KeyframeEntry query = pr.MakeEntry(frame_id, t_ns, T_w_c, path_length, left, det, stereo, ids);
//   std::optional<PlaceMatch> match = pr.Detect(query, det, stereo, ids);
//   pr.Add(std::move(query));   // after relabelling its ids with match->old_landmark
//
// Not thread-safe.

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.h"
#include "core/frame_measurement.h"
#include "core/io/map_file.h"
#include "core/types.h"
#include "frontend/keyframe_database.h"
#include "frontend/matcher.h"
#include "frontend/motion_estimator.h"
#include "frontend/stereo.h"

namespace dala {

struct PlaceRecognitionOptions {
  bool enable = true;  // Loop detection at keyframes.
  // Global descriptor: thumbnail size (pixels) and the shifts searched when comparing.
  int thumbnail_width = 16;
  int thumbnail_height = 10;
  int max_shift_x = 1;
  int max_shift_y = 1;
  // Candidates: appearance score (ZNCC in [-1, 1]) at least this, the best top_k verified.
  // Low: in the rendered city two views 0.5 m apart score ~0.7 and 1 m apart ~0.3 (near walls
  // and ground change fast), other places up to ~0.3; verification decides.
  double min_appearance_score = 0.2;
  int top_k = 3;
  // Keyframes less than this many frames older than the current one are not candidates.
  int min_frame_gap = 100;
  // Spatial gate on the dead-reckoned positions (see the file comment); false: appearance only.
  bool spatial_gate = true;
  double gate_radius_m = 5.0;
  double gate_fraction = 0.05;
  // Stereo: the verified pose's orientation must lie within gate_rotation_deg +
  // gate_rotation_deg_per_m x (path between the keyframes) of the dead-reckoned one. Stereo
  // odometry drifts in heading by thousandths of a degree per metre (KITTI's best: ~0.003);
  // a PnP on a repeated facade seen from elsewhere can put the camera anywhere, facing anywhere
  // (on a rendered 1.26 km drive, a false loop turned it by 176 deg within the position gate).
  // One camera: the estimator applies the same bound to the loop's pose, the path in the map's
  // unit (System copies both into BaLoopClosureOptions::mono_max_turn_deg*).
  double gate_rotation_deg = 10.0;
  double gate_rotation_deg_per_m = 0.01;
  // Verification: matcher (no prior) and PnP (RANSAC + refinement, seeded).
  MatcherOptions matcher;
  MotionEstimatorOptions pnp = DefaultPnpOptions();
  int min_inliers = 30;
  double min_inlier_ratio = 0.3;
  // After a loop, this many keyframes are not searched (one loop edge per revisit is enough
  // for the pose graph; more cost time and add nothing but redundancy); after one the estimator
  // did not close, the next is (LoopNotClosed).
  int keyframes_between_loops = 5;
  // One camera: the gate's radius is this fraction of the path between the two keyframes (map
  // units, no radius in metres: the unit is arbitrary), and an entry keeps at most this many
  // points (its mapped landmarks first, then the strongest corners: ~0.24 MB per keyframe).
  double mono_gate_fraction = 0.05;
  int mono_max_entry_points = 500;
  // One entry per place (issue 14: memory bounded by the place, not the time): a keyframe whose
  // place an older entry already holds is not added to the database (HeldBy). Held: an entry
  // at least min_frame_gap frames old verifies it as a loop would (matcher, PnP or the
  // essential matrix, the spatial gate), with at least min_inliers inliers and
  // place_min_inlier_fraction of the keyframe's own entry points. The entries tried: the one a
  // loop just matched, else the neighbours in time of the entry that held the previous
  // keyframe (a revisit follows the old path). The keyframe stays a keyframe of the
  // estimator; only its appearance is not stored twice.
  bool one_entry_per_place = true;
  double place_min_inlier_fraction = 0.3;
  // Stereo: the held chain predicts where the old entry's points land (the previous keyframe's
  // verified pose and both laps' dead reckoning) and the matcher searches this radius around
  // each prediction instead of the whole image (~10x less work per verification).
  double place_prior_radius_px = 30.0;
  // Relocalisation (Relocalize): after a frame the estimator lost, the whole database is
  // searched for the current place, with neither the spatial gate nor min_frame_gap (the pose
  // after a loss is unknown, and any mapped place will do).
  bool relocalise = true;
  // ...when the frame after a lost one finds fewer than this many of the window's landmarks
  // (frontend.cc: more mean a short loss, which recovers in the window).
  int relocalise_below_mapped = 10;

  static MotionEstimatorOptions DefaultPnpOptions();
  bool IsValid(std::string* why) const;
};

// A verified loop: the message for the estimators, and which current points were matched to
// which old landmark (the frontend relabels them).
struct PlaceMatch {
  LoopDetection loop;
  // Parallel to loop.relabelled: the index of the current point (in the current detection).
  std::vector<int> current_point;
};

// What the last Detect() did (logs, reports, tests).
struct PlaceRecognitionStats {
  int searched = 0;             // Entries old enough.
  int gated_out = 0;            // ...rejected by the spatial gate before matching.
  int candidates = 0;           // Verified (top_k above the score).
  double best_score = -1.0;     // Best appearance score among the old-enough entries.
  FrameId best_frame;           // Its keyframe.
  int best_inliers = 0;         // Inliers of the accepted loop (0: none).
  bool rejected_by_gate = false;  // A candidate passed PnP but its pose failed the gate.
  double ms = 0.0;              // Wall time of Detect().
};

class PlaceRecognition {
 public:
  PlaceRecognition(const StereoRig& rig, const PlaceRecognitionOptions& options);

  // The global descriptor of an 8-bit grey image (CV_32F thumbnail, zero mean, unit norm).
  static cv::Mat GlobalDescriptor(const cv::Mat& gray, const PlaceRecognitionOptions& options);
  // Best ZNCC of two descriptors over the allowed shifts, in [-1, 1].
  static double AppearanceScore(const cv::Mat& a, const cv::Mat& b,
                                const PlaceRecognitionOptions& options);

  // The database entry of a keyframe: its stereo points only (with their landmark ids).
  KeyframeEntry MakeEntry(FrameId frame, int64_t t_ns, const Pose& T_w_c, double path_length_m,
                          const cv::Mat& left, const DetectedImage& detection,
                          const std::vector<std::optional<StereoPoint>>& stereo,
                          const std::vector<LandmarkId>& landmark) const;

  // Searches the database for the place of `query` (an entry made by MakeEntry, not yet added)
  // whose full detection, stereo and landmark ids are given. nullopt: no verified loop.
  std::optional<PlaceMatch> Detect(const KeyframeEntry& query, const DetectedImage& detection,
                                   const std::vector<std::optional<StereoPoint>>& stereo,
                                   const std::vector<LandmarkId>& landmark);

  // Relocalisation after a loss: the place of `query` among ALL entries (no gate, no minimum
  // age, no pause after a loop), ranked by appearance, the top_k verified as in Detect. The
  // match relabels the recognised points as a loop does; the caller's estimator verifies them
  // (PnP on the old landmarks) before trusting them. nullopt: no verified place.
  std::optional<PlaceMatch> Relocalize(const KeyframeEntry& query, const DetectedImage& detection,
                                       const std::vector<std::optional<StereoPoint>>& stereo,
                                       const std::vector<LandmarkId>& landmark);

  // Verifies one old entry against the current keyframe (matcher + PnP, and the spatial gate
  // when `gate`), regardless of appearance. Exposed for tests and tools. With a guess of the
  // current camera in the old one (stereo), the matcher searches place_prior_radius_px around
  // each old point's predicted position only.
  std::optional<PlaceMatch> Verify(const KeyframeEntry& old, const KeyframeEntry& query,
                                   const DetectedImage& detection,
                                   const std::vector<std::optional<StereoPoint>>& stereo,
                                   const std::vector<LandmarkId>& landmark,
                                   bool* rejected_by_gate = nullptr, bool gate = true,
                                   const std::optional<Pose>& T_old_cur_guess = std::nullopt) const;

  // Whether an older entry already holds the place of `query` (see one_entry_per_place): its
  // frame, or nullopt. Call once per keyframe, after Detect (`loop`: what it returned); the
  // caller then leaves `query` out of the database.
  std::optional<FrameId> HeldBy(const KeyframeEntry& query, const std::optional<PlaceMatch>& loop,
                                const DetectedImage& detection,
                                const std::vector<std::optional<StereoPoint>>& stereo,
                                const std::vector<LandmarkId>& landmark);

  void Add(KeyframeEntry entry) { database_.Add(std::move(entry)); }
  // The loop that made the last keyframe's place held was not closed (the estimator refused
  // it): that place is not the old entry's, so the next keyframe is not checked against the
  // old path's next entries either (HeldBy).
  void ForgetHolder() { last_holder_.reset(); }
  // The estimator did not close the last loop Detect found: the next keyframe is searched
  // (keyframes_between_loops counts from a loop that was closed; one that was not corrected
  // nothing, and a better candidate may verify a keyframe later).
  void LoopNotClosed() { keyframes_since_loop_ = kNoLoopYet; }
  // A keyframe of a saved map (core/io/map_file.h) for relocalisation only (loop detection
  // never searches them): its points with a landmark id, in its camera when the landmark has a
  // position in `p_w` (stereo: those only), and its thumbnail as the global descriptor
  // (thumbnail_width x thumbnail_height floats, as the map declares them). The map's keyframes
  // go in their saved order.
  // The caller validates the map (System::UseMap): thumbnails and descriptors of this
  // recognition's sizes (CHECKed), frame ids increasing.
  void AddSavedKeyframe(const SavedKeyframe& keyframe, int patch_size, double patch_spacing,
                        const std::unordered_map<LandmarkId, Eigen::Vector3d>& p_w);
  const KeyframeDatabase& saved_map_database() const { return saved_map_; }
  const KeyframeDatabase& database() const { return database_; }
  KeyframeDatabase* mutable_database() { return &database_; }
  const PlaceRecognitionStats& last_stats() const { return stats_; }
  const PlaceRecognitionOptions& options() const { return options_; }

 private:
  // One camera: the 2D verification of `matches` (see the file comment).
  std::optional<PlaceMatch> VerifyMono(const KeyframeEntry& old, const DetectedImage& detection,
                                       const std::vector<LandmarkId>& landmark,
                                       const std::vector<Match>& matches) const;
  // The match of `old` from the verified `matches` (inlier mask), relabelling the inliers.
  PlaceMatch MakeMatch(const KeyframeEntry& old, const std::vector<LandmarkId>& landmark,
                       const std::vector<Match>& matches, const MotionEstimate& estimate,
                       const std::vector<bool>& inlier) const;
  // The candidates of `query`: entries scoring >= min_appearance_score, best first (ties: older
  // first), at most top_k; `relocalisation`: every entry, no gate; else old enough and gated.
  // Fills the search part of stats_.
  // A relocalisation also ranks the saved map's keyframes.
  std::vector<std::pair<double, const KeyframeEntry*>> RankCandidates(const KeyframeEntry& query,
                                                                      bool relocalisation);
  // Ranks and verifies (RankCandidates, VerifyCandidates; the gate unless `relocalisation`),
  // timing the search into stats_.ms.
  std::optional<PlaceMatch> Search(const KeyframeEntry& query, const DetectedImage& detection,
                                   const std::vector<std::optional<StereoPoint>>& stereo,
                                   const std::vector<LandmarkId>& landmark, bool relocalisation);
  // Verifies the ranked candidates in order; the first verified one.
  std::optional<PlaceMatch> VerifyCandidates(
      const std::vector<std::pair<double, const KeyframeEntry*>>& ranked,
      const KeyframeEntry& query,
      const DetectedImage& detection, const std::vector<std::optional<StereoPoint>>& stereo,
      const std::vector<LandmarkId>& landmark, bool gate);
  // A stereo camera that went at least two gate radii along its path since `old`.
  bool LeftAndCameBack(const KeyframeEntry& old, const KeyframeEntry& query) const;
  // |t_w - query.T_w_c.translation()| within the gate radius of (old, query).
  bool WithinGate(const KeyframeEntry& old, const KeyframeEntry& query,
                  const Eigen::Vector3d& t_w) const;
  // The angle between R_w_cur and query.T_w_c's rotation within the rotation gate of (old,
  // query); stereo only (one camera's verification has no pose: the estimator checks the loop).
  bool WithinRotationGate(const KeyframeEntry& old, const KeyframeEntry& query,
                          const Eigen::Matrix3d& R_w_cur) const;

  StereoRig rig_;
  PlaceRecognitionOptions options_;
  MotionEstimator pnp_;
  KeyframeDatabase database_;
  KeyframeDatabase saved_map_;  // AddSavedKeyframe.
  PlaceRecognitionStats stats_;
  static constexpr int kNoLoopYet = 1 << 30;
  int keyframes_since_loop_ = kNoLoopYet;
  // The entry that held the previous keyframe's place, the previous keyframe in that entry's
  // camera (the verified pose), and the previous keyframe's dead-reckoned pose.
  std::optional<FrameId> last_holder_;
  Pose last_holder_T_old_prev_ = Pose::Identity();
  Pose last_query_T_w_c_ = Pose::Identity();
};

}  // namespace dala

#endif  // DALA_FRONTEND_PLACE_RECOGNITION_H_
