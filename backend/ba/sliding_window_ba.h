#ifndef DALA_BACKEND_BA_SLIDING_WINDOW_BA_H_
#define DALA_BACKEND_BA_SLIDING_WINDOW_BA_H_

// Sliding-window bundle adjustment over the last N keyframes, older keyframes marginalised into
// a linear prior (backend/ba/marginalization.h).
//
// State: the poses T_w_c of the window's keyframes (7-vector blocks on the SE(3) product manifold,
// backend/ba/pose_block.h) and the world points p_w of the landmarks they observe. A landmark
// enters the optimisation when it is seen by at least min_observations window keyframes and has
// an initial position: given by SetLandmarkPosition, its last estimate (if it was marginalised
// before and is seen again), stereo triangulation of its first stereo observation, or, for mono
// observations only, a linear (DLT) triangulation from the window keyframes once the parallax
// exceeds min_triangulation_parallax_deg.
//
// Factors: stereo / mono reprojection (backend/ba/reprojection_factors.h) with a robust loss,
// and the marginalisation prior on the window poses.
//
// Marginalisation (when AddKeyframe finds the window full): the oldest keyframe m leaves, and
// with it the optimised landmarks m observes (the "anchored" scheme of VINS/DSO/Basalt: a
// landmark's observations in the other window keyframes are marginalised together, so the prior
// lives on poses only and stays small: <= 6 (N-1) dimensions). The factors marginalised are all
// observations of those landmarks plus the previous prior. Options::landmark_exit says what
// happens to the landmarks the newest keyframe still tracks (default: they are marginalised into
// the prior AND stay in the state with their other observations, as VINS-Mono does; those
// observations then count twice). A landmark that left the state and is seen again comes back
// as a new variable initialised at its last estimate. docs/backend.md compares the choices.

// Held keyframes (Options::num_held_keyframes, ORB-SLAM's fixed keyframes of the local BA): the
// last keyframes that left the window stay beside it as constants, with their observations of
// landmarks that stayed in the state, so a landmark keeps the constraints of the views that
// first saw it after they leave (the longer its track, the more of the window's scale and
// depth it ties to poses already estimated). What a held keyframe keeps: with a prior, only its
// observations of the landmarks that stayed in the state (the others went into the prior and
// would count twice); without, all of them. Its pose is the estimate when it left, moved by
// ApplyCorrection. The held residuals condition on that value (as ORB-SLAM's local BA does)
// while the prior marginalised the same pose: the information on it is then counted in both,
// an approximation ORB-SLAM, without a prior, does not make (docs/backend.md measures both
// settings). By default 2 with one camera, where the scale lives only in the views (over
// perturbed KITTI and rendered runs the scale drift is smaller with them: docs/monocular.md),
// none in stereo, where every keyframe observes the scale. A held observation
// that fails the outlier test is removed like a window one. A landmark becomes active by its
// window observations only (min_observations), so holding keyframes changes no activation.

// Gauge: in every window solve the oldest num_fixed_keyframes window keyframes are held constant
// (default: 1 for a stereo camera, 2 for a mono one, which also fixes the scale by their
// distance), in every mode. The first keyframes ever added are constants of the prior too; the
// later ones are held only in the solves and stay variables of the marginalisation, so the prior
// is the marginal of all window poses relative to the first keyframes and a solve conditions it
// on the held ones. The prior must not hold the gauge alone: its absolute information decays
// along the path until the whole window drifts as a rigid body (issue 4; IsHeldConstant).
//
// Not thread-safe. Deterministic: the same inputs and options give bit-identical results
// (ordered containers, num_threads = 1 by default).
//
// Usage:
//   SlidingWindowBa ba(K, SlidingWindowBa::Options());
//   for each keyframe: ba.AddKeyframe(kf); SlidingWindowBa::Summary s = ba.Optimize();
//   between keyframes: ba.TrackFrame(observations, T_w_c_predicted, PoseOnlyOptions());

#include <deque>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include "backend/ba/ba_loss.h"
#include "backend/ba/ba_types.h"
#include "backend/ba/disparity_offset_calibration.h"
#include "backend/ba/marginalization.h"
#include "backend/ba/pose_block.h"
#include "backend/ba/pose_only.h"

namespace dala {

class SlidingWindowBa {
 public:
  enum class LandmarkExit {
    // Landmarks the newest keyframe still tracks stay in the state and only the leaving
    // keyframe's observations of them are dropped (information lost, nothing counted twice);
    // the others are marginalised with all their window observations (DSO/Basalt-like).
    kDropTrackedObservations,
    // Every landmark the leaving keyframe sees is marginalised with all its window
    // observations; a track seen again restarts as a new variable (consistent, but the window
    // can lose most of its landmarks at once).
    kMarginalizeAll,
    // As kMarginalizeAll for the prior, but the tracked landmarks stay in the state with their
    // other observations (VINS-Mono-like): their information is counted twice (overconfident),
    // but no track is cut.
    kMarginalizeAllKeepTracks,
    // Landmarks that keep at least min_observations observations in the remaining keyframes
    // stay in the state (non-linear, relinearised at every solve) and only the leaving
    // keyframe's observations of them are dropped, as without a prior; the landmarks that would
    // fall below min_observations are marginalised with their window observations, which a
    // window without a prior would lose (OKVIS-like).
    kDropSharedObservations,
  };

  struct Options {
    int window_size = 8;              // keyframes in the window (>= 2).
    bool use_marginalization = true;  // false: leaving keyframes are dropped (for comparison).
    // What happens to the landmarks the leaving keyframe sees (see the class comment):
    LandmarkExit landmark_exit = LandmarkExit::kMarginalizeAllKeepTracks;
    // Ablation: false => the marginalisation runs (the same landmarks and observations leave
    // the window) but the prior is discarded, and the oldest window keyframes are held constant
    // for the gauge. Shows what the prior carries.
    bool keep_prior = true;
    int num_fixed_keyframes = -1;  // gauge; -1 => 1 for stereo intrinsics, 2 for mono.
    // Keyframes that left the window kept beside it as constants (see the class comment); 0:
    // none; -1: 2 for one camera, 0 for stereo intrinsics (docs/monocular.md, "Held keyframes").
    int num_held_keyframes = -1;
    RobustLoss loss = RobustLoss::kHuber;
    double loss_scale = 2.45;     // on the whitened residual norm; sqrt(5.991), chi2 95% mono.
    int max_num_iterations = 10;  // per solve: the work bound.
    // Per solve; 0 = no time limit (backend/ba/solver_time.h). A positive value is an opt-in
    // budget that makes the run depend on the machine's load (a limit of 0.2 s is hit under
    // load on KITTI); the iteration cap bounds the work instead.
    double max_solver_time_in_seconds = 0.0;
    double function_tolerance = 1e-6;
    // Stereo: estimate the rig's disparity offset delta (StereoIntrinsics::disparity_offset_px)
    // with every window solve, one parameter shared by all stereo residuals, with a prior
    // delta ~ N(0, disparity_offset_prior_sigma_px^2) (a calibrated rig has none; the prior
    // decides when the window cannot: no motion, no depth variety). Why: a real rig's
    // rectification leaves disparities a few tenths of a pixel off (KITTI 06: ~0.3 px too
    // small), which far points turn into a scale error of delta / d; the left-image residuals
    // across keyframes see depth independently of the stereo pair, so delta (an offset) and
    // the scale (a factor on d) separate. Tracking, marginalisation and new stereo landmarks
    // use the last estimate (held constant there).
    bool estimate_disparity_offset = false;
    double disparity_offset_prior_sigma_px = 1.0;
    // Stereo, when estimate_disparity_offset is off: calibrate the offset once for the rig
    // (DisparityOffsetCalibration). After each window solve a second solve on a copy of the
    // window's state, with the offset free, estimates it; the main state does not move with
    // it. The rig's offset becomes the calibrated value when the estimates agree on one
    // (0 until then, and on a rig whose estimates centre on 0).
    bool calibrate_disparity_offset = true;
    // The rig's offset when it is known (a previous run's result, which `dala run` prints in
    // this form): used from the first frame when calibrate_disparity_offset is off (and the
    // start of the per-window estimate with estimate_disparity_offset).
    double disparity_offset_px = 0.0;
    DisparityOffsetCalibration::Options offset_calibration;
    int num_threads = 1;            // > 1 may change the result in the last bits.
    bool remove_outliers = true;    // chi-square 95% test after each solve, then re-solve.
    int max_outlier_rounds = 2;     // re-solves after removing outliers.
    int min_observations = 2;       // a landmark is optimised when seen by >= this many keyframes.
    double min_disparity_px = 0.5;  // stereo triangulation of new landmarks.
    double min_triangulation_parallax_deg = 1;  // mono triangulation of new landmarks.
    double min_depth = 0.05;  // metres; an observation of a point closer (or behind) is an outlier.
    double prior_eigenvalue_floor = 1e-8;  // relative; see marginalization.h.
    // Landmark fusion (FuseLandmarks): the search radius around a landmark's projection in the
    // newest keyframe (pixels); 0: off.
    double fuse_radius_px = 0.0;

    bool IsValid(std::string* why) const;
  };

  struct Summary {
    int num_solves = 0;      // 1 + re-solves after outlier removal.
    int num_iterations = 0;  // over all solves.
    double initial_cost = 0.0;
    double final_cost = 0.0;  // Ceres cost 0.5 sum rho(|r|^2) of the last solve.
    double time_s = 0.0;      // wall time of Optimize().
    int num_keyframes = 0;
    int num_landmarks = 0;  // optimised in the last solve.
    int num_held_keyframes = 0;  // held keyframes with at least one residual in the last solve.
    int num_residual_blocks = 0;
    int num_outliers_removed = 0;
    int num_landmarks_culled = 0;  // dropped because no observation remained.
    bool usable = false;           // Ceres's IsSolutionUsable() of the last solve.

    std::string BriefReport() const;
  };

  struct MarginalizedKeyframe {
    KeyframeId id;
    int64_t t_ns = 0;
    Pose T_w_c;  // the estimate when it left the window.
  };

  SlidingWindowBa(const StereoIntrinsics& K, const Options& options);

  // Gives (or overrides) the world position of a landmark; it is used as the initial value.
  void SetLandmarkPosition(LandmarkId id, const Eigen::Vector3d& p_w);
  // Forgets the last known position of each landmark that no keyframe of the window (or held)
  // observes; the others are kept.
  void ForgetLandmarks(const std::vector<LandmarkId>& ids);

  // Adds a keyframe (kf.T_w_c is the initial guess). When the window is full the oldest keyframe
  // is marginalised (or dropped) first, at the current estimate. CHECKs that ids increase.
  void AddKeyframe(const BaKeyframe& kf);

  // Adds an observation to a keyframe of the window (CHECK: it is in the window), e.g. the
  // previous keyframe's observation of a landmark that a monocular estimator chose at the new
  // keyframe, so that the two views triangulate it in the next Optimize.
  void AddObservation(KeyframeId id, const BaObservation& obs);

  // Loop closure (a pose graph moved the keyframes): sets the window keyframes found in
  // `T_w_kf` to their corrected poses (the others are not in the window: ignored) and drops the
  // marginalisation prior, which was linearised at the old poses and held the old gauge (moving
  // its linearisation points consistently is not worth it for a prior that is off by default);
  // the oldest window keyframe is then held constant, carrying the gauge as the first keyframe
  // did. The relative-pose priors are dropped too (a similarity rescales what they hold). The
  // caller moves the landmarks (SetLandmarkPosition).
  void ApplyCorrection(const std::map<KeyframeId, Pose>& T_w_kf);

  // A relative pose between two added keyframes known apart from their shared landmarks (a mono
  // keyframe bridged from the last one: rotation and direction from their two-view geometry,
  // distance from the last speed), with its information (6x6, [rotation; translation], the
  // right perturbation in the frame b: backend/ba/relative_pose_cost.h). A factor of every
  // window solve while both keyframes are in the window or held, one of them free; it is not
  // marginalised into the prior. Why: a keyframe whose tracks all broke shares few landmarks
  // with the window, and the new ones it starts are seen by it and the keyframe it was bridged
  // from only, so the solve can move it and its new landmarks with a similarity of their own.
  void AddRelativePosePrior(KeyframeId a, KeyframeId b, const Pose& T_a_b,
                            const Matrix6d& information);

  // Landmark fusion (ORB-SLAM's fuse): a point whose track broke and restarted under a new id
  // is one landmark with two ids, each seen by a few keyframes, so the scale and the depth it
  // carries are split between two short tracks. A landmark with a position that the newest
  // keyframe does not observe is projected there (at the keyframe's current estimate); the
  // nearest observation of another landmark with a position within options.fuse_radius_px is
  // its candidate twin (nearest pairs first, each landmark in one pair). The two are merged
  // when no window or held keyframe observes both and one point explains every view of both
  // (at least 3): triangulated from all of them (DLT), each observation passes the outlier test
  // (chi-square 95 %) in front of its camera. The older id survives with every observation of
  // both and the joint triangulation as its position; the newer id is forgotten. Returns the
  // merged pairs (newer id, surviving id); the caller renames the newer id in what it keeps.
  std::vector<std::pair<LandmarkId, LandmarkId>> FuseLandmarks();

  // Optimises the window: solve, reject outliers, re-solve.
  Summary Optimize();

  // Pose-only tracking of a frame against the landmarks currently optimised in the window.
  PoseOnlyResult TrackFrame(const std::vector<BaObservation>& observations, const Pose& T_w_c_guess,
                            const PoseOnlyOptions& options) const;

  std::vector<KeyframeId> WindowKeyframes() const;
  // The held keyframes (oldest first; see Options::num_held_keyframes).
  std::vector<KeyframeId> HeldKeyframes() const;
  std::optional<Pose> KeyframePose(KeyframeId id) const;
  // The window keyframes that hold an observation of the landmark (oldest first).
  std::vector<KeyframeId> ObservingKeyframes(LandmarkId id) const;
  std::optional<Eigen::Vector3d> LandmarkPosition(LandmarkId id) const;
  // The rig's disparity offset as last estimated (StereoIntrinsics::disparity_offset_px; 0
  // until a window solve estimated it, or when Options::estimate_disparity_offset is off).
  double disparity_offset_px() const { return K_.disparity_offset_px; }
  // Replaces the rig's offset (after a global BA estimated it with every keyframe).
  void set_disparity_offset_px(double offset_px) { K_.disparity_offset_px = offset_px; }
  // The rig's disparity-offset calibration (Options::calibrate_disparity_offset), handed from
  // a window to the one that replaces it: the offset is the rig's, not the window's.
  const DisparityOffsetCalibration& offset_calibration() const { return offset_calibration_; }
  void set_offset_calibration(const DisparityOffsetCalibration& calibration) {
    offset_calibration_ = calibration;
  }
  // Landmarks with a position that are currently in the window's map.
  std::map<LandmarkId, Eigen::Vector3d> Landmarks() const;
  const std::vector<MarginalizedKeyframe>& marginalized_keyframes() const { return marginalized_; }
  const MarginalizationPrior& prior() const { return prior_; }
  const Options& options() const { return options_; }

 private:
  struct KeyframeState {
    KeyframeId id;
    int64_t t_ns = 0;
    PoseBlock x;
    bool fixed = false;
    std::vector<BaObservation> observations;
  };

  struct RelativePosePrior {
    KeyframeId a, b;
    Pose T_a_b;
    Matrix6d sqrt_information;
  };

  void MarginalizeOldest();
  // The pose block of a window or held keyframe (nullptr: neither).
  double* BlockOf(KeyframeId id);
  // Forgets the marginalisation prior; the oldest window keyframe then holds the gauge.
  void DropPrior();
  // Moves the leaving keyframe into held_ with the observations that `consumed` (landmarks
  // marginalised into the prior) leaves, dropping the oldest held keyframe beyond the bound.
  void Hold(KeyframeState leaving, const std::set<LandmarkId>& consumed);
  void InitializeStereoLandmarks(const KeyframeState& kf);
  void InitializeMonoLandmarks();
  bool IsActive(LandmarkId id, const std::map<LandmarkId, int>& counts) const;
  std::map<LandmarkId, int> CountObservations() const;
  bool TriangulateMono(LandmarkId id, Eigen::Vector3d* p_w) const;
  bool IsHeldConstant(size_t window_index) const;  // in the window solves (the gauge).
  // Adds the window's (and the held keyframes') poses, their residuals on the active
  // landmarks and the priors to `problem`. `offset`: nullptr = the rig's disparity offset is
  // K_'s constant; else a variable at *offset shared by the stereo residuals (with its prior).
  // with_prior: add the marginalisation prior. Returns the active landmarks; *num_held_used:
  // held keyframes with a residual.
  std::set<LandmarkId> BuildProblem(const std::map<LandmarkId, int>& counts,
                                    ceres::Manifold* manifold, ceres::LossFunction* loss,
                                    double* offset, bool with_prior, ceres::Problem* problem,
                                    int* num_held_used);
  ceres::Solver::Options SolverOptions() const;
  // The window solved again with the disparity offset free, the state restored after: the
  // offset the window would choose (nullopt: no stereo residual, or the solve failed).
  std::optional<double> EstimateOffsetAside();
  // The largest distance between two window keyframes (metres).
  double WindowSpan() const;

  StereoIntrinsics K_;
  Options options_;
  int num_fixed_ = 1;
  int num_held_ = 0;  // Options::num_held_keyframes resolved for the intrinsics.
  int num_added_ = 0;
  std::deque<KeyframeState> window_;
  std::deque<KeyframeState> held_;  // left the window, held constant; oldest first.
  // Last known position of every landmark ever initialised (given, triangulated or estimated);
  // the window's landmarks are those its keyframes observe. std::map: stable addresses for Ceres.
  std::map<LandmarkId, Eigen::Vector3d> landmarks_;
  MarginalizationPrior prior_;
  std::vector<RelativePosePrior> relative_priors_;  // see AddRelativePosePrior.
  std::vector<MarginalizedKeyframe> marginalized_;
  DisparityOffsetCalibration offset_calibration_;
  double prior_offset_px_ = 0.0;  // the disparity offset the prior was built with.
};

}  // namespace dala

#endif  // DALA_BACKEND_BA_SLIDING_WINDOW_BA_H_
