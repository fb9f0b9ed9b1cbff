#ifndef DALA_BACKEND_SLIDING_WINDOW_ESTIMATOR_H_
#define DALA_BACKEND_SLIDING_WINDOW_ESTIMATOR_H_

// SlidingWindowEstimator: the smoothing estimator of dala, for a stereo rig or one camera. It
// feeds the frontend's keyframes into the Ceres sliding-window bundle adjustment
// (backend/ba/sliding_window_ba.h) and tracks the frames between keyframes by a pose-only
// optimisation against the window's landmarks. Stereo and mono share everything but three
// points (stereo = mono + a right-image residual):
//   - the start: stereo starts at the first frame (its points have depth); mono waits for the
//     two-view initialisation (backend/mono/mono_initializer.h): frames until then have no pose
//     and are reported "initialising: <reason>"; on success the reference frame and the current
//     one become the first two keyframes (world = the reference camera, unit = their distance)
//     with the triangulated landmarks, and the frames between them are localised against that
//     map (pose-only), so they get a pose after all;
//   - new landmarks at a keyframe: stereo ones come with their triangulated point; mono ones are
//     chosen among the landmarks the previous keyframe also observed; that observation, and those
//     of every earlier window keyframe on the same track, are added to their keyframes
//     (SlidingWindowBa::AddObservation), and the window triangulates them (DLT over every view,
//     once the rays meet at min_triangulation_parallax_deg). Longest tracks are chosen first, so
//     a new landmark has often been seen by several window keyframes: all of them take it (a
//     longer baseline, and each landmark links more keyframes of the window);
//   - the motion prior: the stereo visual motion is metric; the mono one has no scale, so a mono
//     frame starts from the constant velocity of the estimator's own last two poses, rotated by
//     the frontend's essential-matrix rotation when there is one. A mono frame whose pose-only
//     tracking fails is lost (not valid) and never becomes a keyframe (a keyframe at a guessed
//     pose would triangulate a wrong map); the gauge of a mono window holds two keyframes, which
//     also carries the scale (SlidingWindowBa).
//
// Every frame's pose is stored relative to a keyframe (the keyframe itself: identity; a frame
// between keyframes: T_kf_c from its pose-only estimate), so the trajectory follows later
// corrections of the keyframes (window optimisation): T_w_c = T_w_kf(current estimate) * T_kf_c.
//
// Which observations enter the window: those of landmarks the window already estimates, plus new
// stereo landmarks spread over a grid of image cells (at most max_new_landmarks_per_keyframe per
// keyframe, preferring the longest tracks), so the optimisation stays small (a few hundred
// landmarks) whatever the detector yields.
//
// Motion prior: the frontend's visual motion T_prev_cur chains the previous frame's estimate
// into the initial guess of each frame; when the pose-only optimisation fails the guess is kept
// (the frame is then reported invalid).
//
// Background window solve (options.background_solve, default on): a keyframe's window
// optimisation runs on a worker thread while the caller goes on with the next frame's frontend,
// and the next Add (or any accessor) waits for it first. The result does not depend on timing:
// the solve always ends before the next frame's pose-only tracking, which uses its landmarks,
// and that frame's initial guess starts from the solved keyframe pose. What changes is what Add
// returns for a keyframe: its pose-only estimate before the window solve (the trajectory()
// accessor gives the solved one), and `valid` from the pose-only tracking instead of the solve.
// The frontend never reads the estimator, so the two overlap safely.
//
// Loop closure (a keyframe measurement with `loop`, options.loop.enable): before the keyframe
// joins the window, an SE(3) pose graph over ALL keyframes (backend/ba/pose_graph.h, gauge: the
// first keyframe) is solved with
//   - consecutive edges k -> k+1: the relative pose of the current estimates, information from a
//     drift model: sigma_rot = rot_sigma0 + rot_sigma_per_m * d, sigma_trans = trans_sigma0 +
//     trans_sigma_per_m * d (d = |t_k_k+1|), i.e. the visual-odometry/BA drift grows with the
//     distance travelled (the BA's marginal covariances would cost a Schur complement per
//     keyframe for an information the pose graph only uses relatively);
//   - every loop edge so far (old -> current, the frontend's PnP T_old_cur, covariance the PnP's
//     with a floor of loop_min_sigma_rot/trans, since RANSAC-PnP covariances are optimistic).
// Then keyframe_poses_ and the window take the corrected poses (SlidingWindowBa::ApplyCorrection,
// which drops the marginalisation prior if any), every landmark moves with its anchor keyframe
// (the keyframe that added it): p_w_new = T_w_a_new T_w_a_old^-1 p_w_old, and frames between
// keyframes follow (stored relative to keyframes). The relabelled observations (old landmark
// ids) then join the window at the moved positions.
//
// Refinement (Refine, after the last frame of an offline run): the global BA over every keyframe
// so far, every landmark with a position that two of them observe, and every observation the
// window was given (those the window rejected as outliers too: the global BA runs its own
// chi-square test), each window's gauge keyframes held. Keyframe poses and landmarks take the
// result (and the window, ApplyCorrection); the frames between keyframes follow their keyframe
// (stored relative to it), and in mono their translation is scaled by the keyframe's change of
// local unit (the refined over the old distance to the next keyframe, or the previous one for
// the last), as after a Sim(3) loop closure.
//
// Frames between keyframes (options.refine_frames, default with one camera): a frame that is not
// a keyframe is tracked once, pose-only against the window's landmarks of that moment, and never
// enters the window, while the later keyframes still refine those landmarks (a mono landmark
// starts from the few views it has when it enters, often 1-2 degrees apart). Once the frame's
// keyframe has left the window (and at Refine, for the last ones) the frame is tracked again by the
// same pose-only solver from its stored pose, on all its observations of landmarks that have an
// estimate by then, and T_kf_c takes the result. Tracking, keyframes and the map are unchanged;
// only the frames' own poses move. At most kMaxWaitingFrames wait (a camera that stands still makes
// no keyframe): beyond, the oldest is refined at once. Measured (docs/monocular.md, "Frames between
// keyframes"): with one camera 8 of 10 KITTI start frames gain (one equal, one 0.3 mm worse) and no
// rendered run loses; stereo does (its frames measure depth themselves), so it is off there by
// default.
//
// Culling (options.cull_held_keyframes, default on): a keyframe whose place an older keyframe
// already holds (the frontend verified the old keyframe's view in it: matcher, PnP and at least
// loop.place_min_inlier_fraction of the old view's points as inliers; FrameMeasurement::
// place_held_by; not when that holder is this keyframe's loop and the loop is not closed) is
// redundant with that holder for the map. It still does its work in the window: it carries
// tracks, constrains the window solve, and can close a loop. Once it has left
// the window (and the held keyframes), it is removed: its frames are stored relative to the
// holder, T_holder_c = T_w_holder^-1 T_w_culled T_culled_c (so they follow later corrections of
// the holder, which is physically next to them), the landmarks it anchored move with the holder
// too, those no longer in the window are forgotten (the holder's landmarks describe the place),
// and in the pose graph it is merged into the holder (MergeIntoHolder): the loop edges that ended
// at it end at the holder (composed with T_culled_holder), the edge from the keyframe made before
// it is kept as a measured edge to the holder (from the estimates at the cull), and each
// keyframe's consecutive edge starts at the keyframe made before it or at that one's holder
// (ConsecutiveEdges). Dropping its loop edges instead loses the constraint of the loop that held
// it (docs/backend.md, Culling). A revisit then adds no keyframe to the map once its keyframes
// leave the window: the count is bounded by the places, not by the time spent in them. The gauge
// keyframes of Refine and of each mono map are never culled.

#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "backend/ba/global_ba.h"
#include "backend/ba/pose_graph.h"
#include "backend/ba/sim3_pose_graph.h"
#include "backend/ba/sliding_window_ba.h"
#include "backend/estimator.h"
#include "backend/mono/loop_sim3.h"
#include "backend/mono/loop_turn_gate.h"
#include "backend/mono/mono_initializer.h"
#include "core/camera.h"
#include "frontend/worker_thread.h"

namespace dala {

// The window options used on sequences: marginalisation ON with landmark_exit =
// drop_shared_observations. When a keyframe leaves, the landmarks that keep >= min_observations
// observations stay in the window (non-linear, relinearised at every solve; the leaving
// keyframe's observations of them are dropped) and the others are marginalised into the prior.
// Why this exit: marginalize_all (every landmark the leaving keyframe sees goes into the prior,
// linearised once) was 4-28 % less accurate than no prior on every sequence, because most of the
// window's landmarks were then held by a prior frozen at their first estimates instead of being
// relinearised. drop_shared_observations is within +-1.4 % of no prior everywhere (rover loop
// 0.0314 vs 0.0314 m, without loop closure 0.0676 vs 0.0667, flight 0.1275 vs 0.1258, fast 0.3300
// vs 0.3300, low_texture 0.0329 vs 0.0331, KITTI 06 0.1312 vs 0.1325 m) and keeps the
// information the window would otherwise lose. `--set ba.use_marginalization=0` drops the prior
// (numbers and commands: docs/backend.md).
SlidingWindowBa::Options SequenceBaOptions();

// How the sliding-window estimator closes loops (see the class comment).
struct BaLoopClosureOptions {
  bool enable = true;  // false: loop detections are ignored (the relabelled ids still arrive).
  PoseGraphOptions pose_graph;
  // Drift model of consecutive keyframe edges: sigma = sigma0 + per_m * distance (rad, m).
  double rot_sigma0 = 1e-3;
  double rot_sigma_per_m = 5e-4;
  double trans_sigma0 = 0.01;
  double trans_sigma_per_m = 0.01;
  // Floor on the loop edge's standard deviations (rad, m).
  double loop_min_sigma_rot = 2e-3;
  double loop_min_sigma_trans = 0.02;
  // One camera (Sim(3) graph): standard deviation of the log scale of a consecutive edge (the
  // scale drift per keyframe) and of a loop edge; the loop's similarity from the recognised
  // landmarks (backend/mono/loop_sim3.h).
  double mono_scale_sigma = 0.01;
  double mono_loop_scale_sigma = 0.01;
  // ...and when too few recognised landmarks are mapped on both sides for the similarity: the
  // loop edge from the PnP pose on the old landmarks (at least this many inliers), its scale
  // left to the graph (this log-scale sigma).
  int mono_pnp_min_inliers = 8;
  double mono_pnp_scale_sigma = 1.0;
  LoopSim3Options sim3;
  // One camera: the loop may turn the current keyframe by at most mono_max_turn_deg +
  // mono_max_turn_deg_per_unit x (the keyframe path since the old keyframe, in the map's unit)
  // from its tracked pose; a loop to a look-alike place seen from another street turns it by
  // tens of degrees. System sets these from loop.gate_rotation_deg and
  // loop.gate_rotation_deg_per_m (the stereo rig's gate, frontend/place_recognition.h), and
  // switches the gate off with loop.spatial_gate. The map's unit is the first pair's baseline,
  // so the per-unit term stands for a different distance on each run (KITTI at 10 Hz: ~2 m).
  // The turn is measured from the pose the current map gives the frame (the loop's relabelled
  // observations do not place it), else from the constant-velocity prediction
  // (SlidingWindowEstimator::Add).
  bool mono_turn_gate = true;
  double mono_max_turn_deg = 10.0;
  double mono_max_turn_deg_per_unit = 0.01;

  bool IsValid(std::string* why) const;
};

struct SlidingWindowEstimatorOptions {
  SlidingWindowBa::Options ba = SequenceBaOptions();
  PoseOnlyOptions pose_only;
  int max_new_landmarks_per_keyframe = 120;
  int grid_cols = 8;  // Cells of the new-landmark selection grid.
  int grid_rows = 5;
  BaLoopClosureOptions loop;
  bool background_solve = true;  // see the class comment.
  // Keyframe culling (see the class comment, "Culling"): a keyframe whose place an older
  // keyframe holds (FrameMeasurement::place_held_by) is removed once it has left the window.
  bool cull_held_keyframes = true;
  // The frames between keyframes are tracked (pose-only) against landmarks that later keyframes
  // still refine; each is tracked again against the refined landmarks once its keyframe has
  // left the window (see the class comment, "Frames between keyframes"). "mono" (default): with
  // one camera only; "always"; "off".
  std::string refine_frames = "mono";
  // The pixel sigma of the keyframes' observations in the window's solves and the global BA:
  // their Huber loss bends at ba.loss_scale sigma and the outlier test rejects a residual beyond
  // sqrt(chi2_95(dof)) sigma. -1: by mode, 0.35 px with one camera, 0.5 px with a stereo rig
  // (docs/results.md, "ba.sigma_px"). The frontend's stereo.sigma_px (1 px) is the EKFs'
  // measurement noise and the stereo triangulation's covariance.
  double observation_sigma_px = -1.0;
  // The pixel sigma of a frame's observations when the frame is placed against the window: the
  // pose-only tracking and its outlier test, the PnP recovery's refinement, the refinement of
  // frames between keyframes. Wider than the window's: a fast forward frame's constant-velocity
  // guess against a young map is not within a fraction of a pixel, and a tight test would drop
  // nearly every observation and lose the frame.
  double tracking_sigma_px = 1.0;
  // observation_sigma_px with -1 resolved for the rig.
  double WindowSigmaPx(const StereoRig& rig) const;
  // One camera: the two-view initialisation, its pair checked by the next frame.
  MonoInitializerOptions mono_init = [] {
    MonoInitializerOptions o;
    o.next_frame_min_inlier_ratio = 0.5;
    return o;
  }();
  // The order of the correspondences handed to OpenCV's RANSAC in the mono PnP recovery, which
  // is what seeds its draws (core/ransac_order.h): 0 as given.
  uint64_t ransac_order_seed = 0;
  // One camera: after this many lost frames in a row (PnP recovery failing too: the map is out
  // of view), a new map is initialised and placed where the old one would continue.
  int mono_reinit_after_lost_frames = 10;
  // One camera: a frame neither tracked nor recovered is placed by the two-view geometry with
  // the last keyframe, scaled by the last speed (BridgeFromLastKeyframe).
  bool mono_bridge = true;
  // Refine() (System::Finish, `dala run` after the last frame): the global BA over every
  // keyframe (backend/ba/global_ba.h). When: "off", "always", "after_loop" (a run that
  // closed a loop: the pose graph moved the keyframes with an approximate model, and the global
  // BA spreads the loop's correction over every observation, as ORB-SLAM's global BA after a
  // loop does), or "rig_offset" (a stereo rig whose disparity offset the online calibration
  // found non-zero: the keyframes that left the window before the offset was known kept the
  // scale error it causes, and the global BA re-solves every keyframe with the offset free; or
  // whose offset was given, ba.disparity_offset_px: re-solved with it held).
  // Not "always": on exact rendered rigs and KITTI it is better on some runs and worse on
  // others (docs/backend.md, "Global BA after the run"); whenever it runs on a rig with a
  // calibrated offset, the offset is free in it.
  std::string final_ba = "rig_offset";
  GlobalBaOptions global_ba;

  bool IsValid(std::string* why) const;
  // IsValid and what the rig adds (one camera: a gauge of at least two held keyframes).
  bool IsValidFor(const StereoRig& rig, std::string* why) const;
};

class SlidingWindowEstimator : public Estimator {
 public:
  // A stereo rig (baseline > 0) runs the stereo estimator, a monocular one (baseline 0) the
  // mono estimator; the camera must be rectified (no distortion).
  SlidingWindowEstimator(const StereoRig& rig, const SlidingWindowEstimatorOptions& options);

  std::string name() const override { return "ba"; }
  std::string mode() const override { return rig_.is_stereo() ? "stereo" : "mono"; }
  EstimatorOutput Add(const FrameMeasurement& measurement) override;
  Trajectory trajectory() const override;
  std::vector<MapPoint> map() const override;
  bool UseMap(const std::vector<MapPoint>& landmarks) override;
  // The global BA (see the class comment, "Refinement").
  RefinementSummary Refine(const std::function<bool()>& stop_requested) override;
  std::string DisparityOffsetNote() const override;
  std::optional<double> DisparityOffsetPx() const override;

  const SlidingWindowBa& ba() const {
    WaitForWindowSolve();
    return ba_;
  }
  int num_keyframes() const { return num_keyframes_; }
  // Keyframes in the map now: those made, minus those culled.
  int num_keyframes_in_map() const { return static_cast<int>(keyframe_poses_.size()); }
  int num_loops_closed() const { return loops_closed_; }

 private:
  struct FrameRecord {
    int64_t t_ns = 0;
    KeyframeId reference;
    Pose T_kf_c = Pose::Identity();
    bool has_pose = true;  // false: lost, or before the mono initialisation (not in trajectory()).
  };
  // Frames between keyframes waiting to be tracked again (options_.refine_frames): the index in
  // frames_ and every observation of the frame (the landmarks mapped since count too).
  struct WaitingFrame {
    size_t index = 0;
    std::vector<BaObservation> observations;
  };
  // Mono: feeds the initializer; on success builds the first two keyframes and localises the
  // frames between them.
  EstimatorOutput AddBeforeInitialization(const FrameMeasurement& m);
  // Returns how many frames before the reference it placed (PlaceEarlierFrames).
  int StartMonoMap(const MonoInitialization& init);
  // The frames before the first map's reference (init.earlier, given up with older references)
  // localised in the new map, latest first, until one fails; returns how many.
  int PlaceEarlierFrames(const MonoInitialization& init, size_t reference_index,
                         KeyframeId reference, KeyframeId current);
  // Mono, after each tracked frame: the last tracked pose and velocity; after a lost one: no
  // pose, and after mono_reinit_after_lost_frames of them a re-initialisation.
  void NoteMonoTracking(const FrameMeasurement& m, bool valid, const Pose& T_w_c,
                        EstimatorOutput* out);
  // Starts the map of `init` (StartMonoMap; after a loss in a window of its own) and spends the
  // initializer; the note that says so. `current_reported`: init.current is the last frame
  // added (reported without a pose: initialising, or lost during a re-initialisation), not the
  // one being added.
  std::string StartMapFrom(const MonoInitialization& init, bool current_reported);
  // The new map's reference camera in the world after a re-initialisation (see the .cc).
  Sim3 PlaceReinitializedMap(const MonoInitialization& init) const;
  // The initial guess of the current frame's pose (see the class comment).
  Pose PredictPose(const FrameMeasurement& m) const;
  // When pose-only tracking from the predicted pose fails, the pose from every observation
  // of a landmark with a position (the window's and older ones: relocalisation in the map) by
  // RANSAC PnP (OpenCV EPnP, seeded), then pose-only over them; nullopt if too few agree.
  std::optional<Pose> RecoverPose(const FrameMeasurement& m) const;
  // RANSAC PnP (OpenCV EPnP, seeded) on m's observations of the landmarks `use` accepts that
  // have a position, then pose-only over them; nullopt with fewer than min_inliers inliers.
  std::optional<Pose> PnpPose(const FrameMeasurement& m, const std::function<bool(LandmarkId)>& use,
                              int min_inliers) const;
  // Mono, when neither pose-only tracking nor RecoverPose places m: its pose from the two-view
  // geometry with the last keyframe (backend/mono/keyframe_bridge.h), the step's length from the
  // last tracked speed; *note says so. nullopt when the pair fails the two-view tests.
  // `note`: the bridged frame's note; `why_not`: appended with the reason when there is none.
  std::optional<Pose> BridgeFromLastKeyframe(const FrameMeasurement& m, std::string* note,
                                             std::string* why_not) const;
  // The two-view tests of a bridge (mono_init's, with fewer points).
  TwoViewOptions BridgeTwoViewOptions() const;
  // Mono: keyframe `id` (frame m) is the last one; its observations are the candidates for new
  // landmarks at the next keyframe.
  void RememberLastKeyframe(KeyframeId id, const FrameMeasurement& m);
  // Adds kf to the window and to what Refine solves (the observations, the window's gauge).
  void AddToWindow(const BaKeyframe& kf, const FrameMeasurement& m);
  // landmarks_in_state and local_map of `out` from the window.
  void ReportLandmarks(EstimatorOutput* out) const;
  Pose KeyframePoseNow(KeyframeId id) const;
  std::vector<BaObservation> SelectKeyframeObservations(const FrameMeasurement& m,
                                                        const Pose& T_w_c);
  // A frontend observation as a keyframe's in the window's solves (WindowSigmaPx), and as a
  // frame's placed against the window (tracking_sigma_px).
  BaObservation AsKeyframeObservation(const FeatureObservation& o) const;
  BaObservation AsFrameObservation(const FeatureObservation& o) const;
  std::vector<BaObservation> WindowObservations(const FrameMeasurement& m) const;
  // Solves the pose graph with the new loop edge (old keyframe -> the keyframe `cur_id` about
  // to be added at *T_w_c) and applies the correction; false (nothing changed) if the old frame
  // is not a keyframe or the solve fails, *why_not then says which (the frame's note).
  bool CloseLoop(const LoopDetection& loop, KeyframeId cur_id, Pose* T_w_c, std::string* why_not);
  // One camera (m.loop, *T_w_c tracked): the same over Sim(3) (backend/ba/sim3_pose_graph.h);
  // the loop edge places the keyframe by PnP of m on the old landmarks (else by the similarity)
  // with the scale of the recognised landmarks' two estimates (else left to the graph). Frames
  // between keyframes are rescaled with their keyframe; the previous frame's pose follows.
  // Refused (false, *why_not says why) when the loop would turn the camera beyond the gate
  // (MonoLoopTurn), when neither a similarity nor a PnP places the keyframe among the old
  // landmarks, or when the old frame is not a keyframe or the graph's solve fails.
  bool CloseMonoLoop(const FrameMeasurement& m, KeyframeId cur_id, Pose* T_w_c,
                     std::string* why_not);
  // One camera: how far a loop that puts the current keyframe (tracked at T_w_c) at T_w_c_loop
  // turns it, and whether that is within the gate (BaLoopClosureOptions::mono_max_turn_deg;
  // always within with the gate off); logs a refusal.
  LoopTurn MonoLoopTurn(KeyframeId old, const Pose& T_w_c, const Pose& T_w_c_loop,
                        FrameId old_frame) const;
  // A new, empty window (no marginalisation prior); every landmark keeps its last position
  // (PnP recovery, loop closure and the next keyframes use them), the disparity offset its
  // estimate; the last keyframe's observations are forgotten (it left with the window).
  void RestartWindow();
  // Mono, re-initialising after a long loss: the pose of m by PnP on the old map's landmarks
  // (the frontend relocalised it); on success the re-initialisation stops and the old map goes
  // on. nullopt: not relocalised.
  std::optional<Pose> ResumeOldMap(const FrameMeasurement& m);
  // m sees too few of the window's landmarks and enough older ones: relocalised at a place the
  // window does not hold.
  bool OutsideWindow(const FrameMeasurement& m) const;
  // Optimises the window with the new keyframe `id` and records the new estimates
  // (keyframe_poses_, map_points_). Runs on solver_ when options_.background_solve.
  void SolveWindow(KeyframeId id);
  // Culls every keyframe of held_by_ that has left the window (and its held keyframes); see
  // the class comment, "Culling".
  void CullHeldKeyframes();
  void CullKeyframe(KeyframeId culled, KeyframeId holder);
  // The pose graph's part of a cull (sliding_window_loop_closure.cc): the culled keyframe's
  // edges move to its holder (see the class comment, "Culling").
  void MergeIntoHolder(KeyframeId culled, KeyframeId holder);
  // The node before keyframe k in the made order: k - 1, or the holder it was merged into.
  KeyframeId GraphPredecessor(KeyframeId k) const;
  // The consecutive edges (from, to) of a pose graph over `nodes`: each node from its
  // GraphPredecessor (the previous node when that one is not a node).
  template <typename Node>
  std::vector<std::pair<KeyframeId, KeyframeId>> ConsecutiveEdges(
      const std::map<KeyframeId, Node>& nodes) const;
  // Frames between keyframes (see the class comment): frames_[index] (tracked from m) waits to
  // be tracked again, when options_.refine_frames says so for this rig.
  void DeferFrameRefinement(size_t index, const FrameMeasurement& m);
  // Tracks again the waiting frames whose keyframe has left the window (all of them: `all`),
  // against the latest landmark estimates.
  void RefineWaitingFrames(bool all);
  // One of them (a frame whose new tracking fails keeps its pose).
  void RefineFrame(const WaitingFrame& waiting);
  // Landmark fusion (SlidingWindowBa::FuseLandmarks, before each window solve): the newer id of
  // each merged pair is renamed to the surviving one in everything the estimator keeps, and in
  // every later measurement (the frontend goes on tracking the point under the newer id).
  void RenameFused(const std::vector<std::pair<LandmarkId, LandmarkId>>& fused);
  // m with fused ids renamed (a frame that holds both ids of a pair keeps the renamed track's
  // observation: the other is the local map's guess at the same point).
  FrameMeasurement WithFusedIds(const FrameMeasurement& m) const;
  // Blocks until a background window solve has finished (no-op when none is running).
  void WaitForWindowSolve() const { solver_.Wait(); }
  // A stereo rig whose disparity offset is calibrated online (ba.calibrate_disparity_offset, not
  // the per-window estimate).
  bool CalibratesRigOffset() const;
  // Refine will need observation_archive_ (options_.final_ba; "rig_offset": a stereo rig whose
  // offset is calibrated online, which only the end of the run can tell is non-zero).
  bool KeepsObservationArchive() const;
  // A stereo rig whose disparity offset is given (ba.disparity_offset_px, not 0, with the
  // calibration off).
  bool KnowsRigOffset() const;
  // A stereo rig with a non-zero disparity offset, calibrated online or given.
  bool RigHasOffset() const;

  StereoRig rig_;
  SlidingWindowEstimatorOptions options_;
  SlidingWindowBa ba_;
  std::vector<FrameRecord> frames_;
  std::deque<WaitingFrame> waiting_frames_;    // Oldest first (see DeferFrameRefinement).
  std::map<KeyframeId, Pose> keyframe_poses_;  // Last estimate of every keyframe.
  std::map<LandmarkId, int> landmark_observations_;
  std::map<LandmarkId, Eigen::Vector3d> map_points_;  // Last estimate of every landmark.
  std::map<LandmarkId, KeyframeId> anchor_;           // The keyframe that added the landmark.
  std::map<FrameId, KeyframeId> keyframe_of_frame_;
  std::map<KeyframeId, size_t> first_frame_of_keyframe_;  // Its index in frames_.
  // Keyframes to cull once they leave the window, and the keyframe holding each one's place.
  std::map<KeyframeId, KeyframeId> held_by_;
  // The measured edges of the pose graph: every loop closed so far, and the edges culled
  // keyframes left to their holders (see the class comment, "Culling").
  std::vector<PoseGraphEdge> loop_edges_;
  int loops_closed_ = 0;
  std::map<KeyframeId, KeyframeId> merged_into_;  // Culled keyframe -> its holder.
  // The offset the online calibration had found, when Refine re-estimated it.
  std::optional<double> online_offset_px_;
  // For Refine (kept only when KeepsObservationArchive()): every track of each keyframe (the
  // frontend's observations; those the window never mapped are triangulated first), as
  // (keyframe, observation);
  // and the keyframes each window held as its gauge (the first one or two after each restart).
  std::vector<std::pair<KeyframeId, BaObservation>> observation_archive_;
  std::set<KeyframeId> gauge_keyframes_;
  std::vector<std::pair<KeyframeId, KeyframeId>> unit_pairs_;  // Mono: (first, second) per map.
  int added_since_window_start_ = 0;
  std::vector<Sim3Edge> mono_loop_edges_;  // One camera: the same, in the current units.
  // One camera: old landmarks a loop that was not closed relabelled, unused until a loop to
  // them closes (see Add).
  std::set<LandmarkId> unconfirmed_loop_landmarks_;
  // Landmark fusion: each merged id -> the id that survived it (see RenameFused), and back.
  std::map<LandmarkId, LandmarkId> fused_into_;
  std::multimap<LandmarkId, LandmarkId> fused_from_;
  Pose T_w_prev_ = Pose::Identity();
  Pose velocity_ = Pose::Identity();  // T_prev_cur of the last frame.
  // Mono: the initializer until the map exists, and every observation of the last keyframe
  // (the candidates for new landmarks at the next one).
  std::optional<MonoInitializer> initializer_;
  struct Reinit {  // The last tracked frame: where a re-initialised map continues from.
    int64_t t_ns = 0;
    Pose T_w_c = Pose::Identity();
    Eigen::Vector3d velocity_w = Eigen::Vector3d::Zero();  // World frame, per second.
  };
  std::optional<Reinit> last_tracked_;
  std::optional<Reinit> reinit_;  // Set while re-initialising.
  int lost_streak_ = 0;
  // A frame was placed by RecoverPose since the last keyframe (see Add).
  bool relocalised_ = false;
  // UseMap: no frame placed in the saved map yet.
  bool awaiting_map_ = false;
  KeyframeId last_keyframe_;
  std::map<LandmarkId, BaObservation> last_keyframe_observations_;
  // Mono: every observation of the other window keyframes (by keyframe), the earlier views a
  // new landmark takes with the last keyframe's.
  std::map<KeyframeId, std::map<LandmarkId, BaObservation>> earlier_keyframe_observations_;
  int num_keyframes_ = 0;
  // The keyframe whose window solve ran in the background since the last Add (its solved pose
  // becomes the next frame's starting point).
  std::optional<KeyframeId> solved_in_background_;
  // Declared last: destroyed (its thread joined, any solve finished) before the state it uses.
  mutable WorkerThread solver_;
};

}  // namespace dala

#endif  // DALA_BACKEND_SLIDING_WINDOW_ESTIMATOR_H_
