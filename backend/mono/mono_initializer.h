#ifndef DALA_BACKEND_MONO_MONO_INITIALIZER_H_
#define DALA_BACKEND_MONO_MONO_INITIALIZER_H_

// MonoInitializer: the start of every monocular estimator. It holds the frontend's measurements
// from a reference frame on, and at each new frame tries the two-view initialisation
// (backend/mono/two_view.h) between the reference and the new frame on the landmarks both
// observe (the frontend's tracks carry the ids). Until it succeeds every frame is reported
// "initialising: <reason>" and given no pose.
//
// The reference frame: the first frame with at least min_reference_features observations. It
// is replaced by the current frame when fewer than two_view.min_points of its landmarks are
// still tracked (the two-view test could never pass), or when it is older than
// max_pending_frames (the motion stayed too small for too long); the frames before the new
// reference then stay without a pose. When the reference's tracks are gone, the oldest frame
// since then that shares at least min_reference_features landmarks with the current frame is
// tried first as the current frame's reference, and initialises the map if that pair passes
// (moving fast forward, a reference loses its tracks within two or three frames while a
// frame's motion alone has too little parallax).
//
// On success: the reference frame (world frame = its camera), the frames in between (which the
// estimator localises afterwards against the new map), the frames before the reference since
// the initialiser started (at most kMaxEarlierFrames, the latest; those of references given up:
// the estimator localises them too where they share enough of the new map's landmarks) and the
// current frame with
// T_ref_cur (|t| = 1: the map's unit is this first baseline) and the triangulated landmarks
// p_ref, refined by a two-view bundle adjustment, the essential matrix sampled twice
// (backend/mono/refined_two_view.h).
//
// Not thread-safe; deterministic.

#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "backend/mono/two_view.h"
#include "core/camera.h"
#include "core/frame_measurement.h"

namespace dala {

// The frames before the reference that an initialisation hands over (~20 KB each).
inline constexpr size_t kMaxEarlierFrames = 30;

struct MonoInitializerOptions {
  TwoViewOptions two_view;
  int min_reference_features = 100;
  int max_pending_frames = 60;  // Reference older than this: a new reference.
  bool refine = true;           // Two-view BA of the accepted reconstruction.
  // The next frame checks an accepted pair (0: no check): a PnP (seeded RANSAC, 2.45 px) of the
  // pair's points in it must keep at least this fraction of those it observes, else the pair is
  // dropped and the initialiser goes on with the next frame as the current one (a frame that
  // sees fewer than 6 of the points is no evidence: the pair is kept). The pairs measured keep
  // 88-100 %; a pair whose points do not fit one pose of the next frame keeps fewer (a wrong
  // reconstruction that is consistent in itself can pass). The estimator
  // then tracks the checking frame in the new map: it was matched by the frontend before the
  // map existed (docs/monocular.md, "The first pair checked by the next frame").
  double next_frame_min_inlier_ratio = 0.0;

  bool IsValid(std::string* why) const;
};

struct MonoInitialization {
  FrameMeasurement reference;
  // Frames given up with their references (oldest first), before `reference`.
  std::vector<FrameMeasurement> earlier;
  std::vector<FrameMeasurement> between;  // After the reference, before the current frame.
  FrameMeasurement current;
  // The frame after `current` that checked the pair (next_frame_min_inlier_ratio > 0); the
  // estimator tracks it in the new map. nullopt without the check.
  std::optional<FrameMeasurement> next;
  Pose T_ref_cur = Pose::Identity();            // |translation| = 1.
  std::map<LandmarkId, Eigen::Vector3d> p_ref;  // Landmarks in the reference camera.
  TwoViewResult two_view;
  bool magsac = false;  // The motion is MAGSAC++'s (backend/mono/refined_two_view.h).

  // The model and the sampler that gave the motion, for notes: "essential", "homography",
  // "essential (MAGSAC++)".
  std::string ModelName() const;
};

class MonoInitializer {
 public:
  MonoInitializer(const PinholeCamera& camera, const MonoInitializerOptions& options);

  // Feeds the next frame; returns the initialisation when it succeeds at this frame (the
  // initializer is then spent: call Reset to start again): with the next-frame check, the pair
  // found at the frame before, checked by this one (MonoInitialization::next). When it does not,
  // reason() says why.
  std::optional<MonoInitialization> Add(const FrameMeasurement& m);
  // The pair waiting for its next frame's check, unchecked (the run ended before that frame);
  // the initializer is then spent. nullopt when no pair waits.
  std::optional<MonoInitialization> TakeWaitingPair();
  // "no reference frame yet (N features < 100)", "too little parallax: ...", etc.
  const std::string& reason() const { return reason_; }
  void Reset();

 private:
  // The landmarks `reference` and `m` both observe: their pixels in each and their ids.
  struct Correspondences {
    std::vector<Eigen::Vector2d> uv_ref, uv_cur;
    std::vector<LandmarkId> ids;
  };
  static Correspondences Correspond(const FrameMeasurement& reference, const FrameMeasurement& m);
  // The two-view initialisation of the pair (reference, m) on their correspondences c
  // (`between` left empty); nullopt with *why_not when the pair fails its tests.
  std::optional<MonoInitialization> TryPair(const FrameMeasurement& reference,
                                            const FrameMeasurement& m, const Correspondences& c,
                                            std::string* why_not) const;

  // Add without the next-frame check: the pair found at m, if any.
  std::optional<MonoInitialization> FindPair(const FrameMeasurement& m);
  // The fraction of the pair's points that m observes and a PnP keeps (0 with fewer than
  // kMinObservedToCheck), and how many it observes.
  double NextFrameInlierRatio(const MonoInitialization& pair, const FrameMeasurement& m,
                              int* observed) const;

  // Keeps the frames of a reference given up (the reference and the first `count` frames after
  // it) in earlier_, the latest kMaxEarlierFrames.
  void GiveUp(size_t count);

  PinholeCamera camera_;
  MonoInitializerOptions options_;
  std::optional<FrameMeasurement> reference_;
  std::vector<FrameMeasurement> between_;
  std::deque<FrameMeasurement> earlier_;
  std::optional<MonoInitialization> pair_;  // Found, waiting for the next frame's check.
  std::string reason_;
};

}  // namespace dala

#endif  // DALA_BACKEND_MONO_MONO_INITIALIZER_H_
