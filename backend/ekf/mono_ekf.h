#ifndef DALA_BACKEND_EKF_MONO_EKF_H_
#define DALA_BACKEND_EKF_MONO_EKF_H_

// MonoEkfEstimator: the paper's bearing-only EKF-SLAM with delayed, multi-hypothesis (Gaussian
// sum) landmark initialisation (Lemaire et al. 2007, section "monocular"; Lemaire, Lacroix, Sola,
// IROS 2005).
//
// State (backend/ekf/ekf_state.h): the camera pose T_w_c (right error, [phi; rho]) and Euclidean
// landmarks p_w with the full covariance; the world frame is the first camera (the two-view
// reference camera with the constant-velocity model).
//
// Two predictions, chosen once per run by options.prediction:
// * "motion" (the paper): the motion that fixes the scale: m.odometry when present, else m.motion
//   when motion.scale_known (stereo visual motion used as dead reckoning, as on the paper's
//   robots); T_w_cur = T_w_prev T_prev_cur, F = Adj(T_prev_cur^-1), G = I. With neither, no
//   prediction: the pose is kept, its covariance inflated (lost_*_sigma), the frame reported not
//   valid.
// * "constant_velocity" (one camera, no motion input; MonoSLAM / RT-SLAM): the state also holds
//   the camera's twist w = [omega; nu] per second in the camera frame (EkfState with_velocity);
//   T_w_cur = T_w_prev Exp(w dt), w_cur = w_prev + V (dt from the timestamps), V ~ N(0, Q_V dt):
//   a velocity random walk (white acceleration), Q_V = diag(sa^2 I3, (sl |nu_0|)^2 I3) with
//   sa = cv_angular_acceleration_sigma (rad s^-3/2) and sl = cv_linear_acceleration_sigma (s^-1/2)
//   relative to the initial speed |nu_0| (the map's unit is arbitrary: the first baseline).
//   Jacobians and covariance propagation: EkfState::PredictConstantVelocity. Observations do not
//   involve w: it is corrected through its correlation with the pose.
//   The scale comes from the two-view initialisation (backend/mono/mono_initializer.h, options
//   mono_init): until it succeeds every frame is reported `initializing` with no pose ("initialising:
//   <reason>"). On success at frame c with reference frame r: world = camera r (pose identity, in
//   the trajectory), T_w_c = T_ref_cur (|t| = 1) with covariance diag(init_rotation_sigma^2,
//   init_translation_sigma^2) (chosen, not propagated from the two-view BA); the frames between
//   get no pose. Landmarks: the triangulated points, with the covariance of their two-view
//   triangulation (poses fixed): C = (sum_{v = r, c} H_v^T H_v / s^2)^-1, H_v = d uv_v / d p_r, so
//   the depth uncertainty grows as the parallax shrinks; inserted, independent of the pose, when
//   their relative depth sigma is below alpha (as well known as one Gaussian-sum hypothesis), the
//   best init_per_zone per image zone. They are not updated with the frame c observations (already
//   used). Initial velocity: the mean over the span, w_0 = Log(T_ref_cur) / (t_c - t_r), with
//   covariance Q_V (t_c - t_r) (the random walk over the span).
//   The pose buffer of the candidates records the estimated step T_prev_cur = T_w_prev^-1 T_w_cur
//   with covariance J P_ww J^T, J = J_r(w dt) dt (the velocity's posterior uncertainty over the
//   step) in place of a motion input's covariance.
// * "auto" (default): "motion" when the stream carries a motion input, else "constant_velocity".
//   Decided at the first frame when it is stereo (its visual motion is metric), else at the
//   second (the first that can carry odometry or a motion): frame 0 is processed as in "motion"
//   (pose identity) and given to the two-view initializer; switching to "constant_velocity"
//   there discards that start (frame 0 keeps its pose only if it becomes the two-view reference,
//   as it normally does).
//
// Observation of a landmark in the state: z = uv = pi(K, T_w_c^-1 p_w), R = s^2 I2,
// H = d_uv_d_pc [[p_c]x, -I | R_w_c^T]; gated by chi2_2(99 %) = 9.21, batched symmetric update.
//
// Initialisation of a new feature (first seen at frame k, camera T_k = (R_k, t_k), pose
// covariance P_k, unit ray b_c = normalise(K^-1 [u v 1]), d = R_k b_c in the world):
//   Gaussian sum along the ray, geometric series between d_min and d_max:
//     s_0 = d_min / (1 + alpha), sigma_i = alpha s_i, s_{i+1} = beta s_i,
//     beta = (1 + alpha k_sigma) / (1 - alpha k_sigma), until s_i + sigma_i >= d_max;
//     x_i = t_k + s_i d,  Sigma_i = d sigma_i^2 d^T + s_i^2 Sigma_d + J_i P_k J_i^T,
//     Sigma_d = R_k (d b_c / d uv) s^2 I2 (d b_c / d uv)^T R_k^T (angular uncertainty of the ray),
//     J_i = [-R_k [s_i b_c]x, R_k] (uncertainty of the pose at the first observation).
//   Each later observation z_j (frame j, pose T_j with covariance P_j from the pose buffer) is used
//   only when the image motion since the last used one is significant:
//     |uv_j - uv_last|^2 / (2 s^2) > min_image_motion_chi2 (~8).
//   Hypothesis i, a Gaussian (p_k, C_k) in the first camera starting at (s_i b_c,
//   b sigma_i^2 b^T + s_i^2 Sigma_b), is scored in the current camera j through the relative pose
//   T_j_k (the filter's estimates; uncertainty Sigma_jk accumulated from the motion inputs since
//   k, see RelativeCovariance): r = z_j - pi(T_j_k p_k), H_k = H R_jk,
//   S = H_k C_k H_k^T + H J Sigma_jk J^T H^T + s^2 I, J = [-R_jk [p_k]x, R_jk], and then updated
//   by its own Kalman step (a Gaussian-sum filter; a static Gaussian would be charged log det S at
//   every step, which biased the test towards far hypotheses). The absolute pose uncertainties of
//   frames k and j are mostly common drift and say nothing about depth, hence the relative pose.
//   Dropped
//   when r^T S^-1 r > prune_chi2 (~20), else its log-likelihood
//   L_i += -r^T S^-1 r / 2 - log(2 pi sqrt(det S)).
//   Hypotheses that converged onto the best one (means within one sigma) are merged into it.
//   SPRT against the best other hypothesis: LLR_i = L_i - max_{k != i} L_k; pruned when
//   LLR_i < ln(a_MD / (1 - a_FA)), winner when LLR_i > ln((1 - a_MD) / a_FA).
//   When one wins or one remains, the landmark is inserted (delayed initialisation), relative to
//   the current camera c: the winning Gaussian, moved into c through T_c_k = T_w_c^-1 T_w_k
//   (prior mean T_c_k s_i b_k, covariance R_c_k (b sigma_i^2 b^T + s_i^2 Sigma_b) R_c_k^T +
//   J Sigma_ck J^T), is refined by replaying the stored observations j as updates of the point
//   alone, z_j = pi(T_c_j^-1 p_c), noise s^2 I + H_T Sigma_cj H_T^T, where Sigma_cj is the
//   uncertainty of the relative pose T_c_j accumulated from the motion inputs between j and c
//   (RelativeCovariance), counted n times for n replayed observations since these relative-pose
//   errors share motion segments (covariance intersection). The replay is iterated to convergence
//   (Gauss-Newton: one EKF pass linearised one alpha-sigma off in depth is overconfident); a
//   refined point whose cost exceeds the chi2 99.9 % region is dropped. The point (p_c, C) is then
//   augmented like a stereo point (ekf_state.h) with the full cross-covariance to the current pose.
//   Anchoring it at the current pose with a relative covariance matters: expressing the point in
//   the world with the absolute pose uncertainties of frames k..j and then correlating it with the
//   current pose gives a joint covariance that is not conservative (the pose NEES diverged within
//   20 frames). If no hypothesis remains the feature is dropped (and its id not retried).
// Points at infinity: when the farthest hypothesis is still alive after `infinity_after_frames`
//   frames (the parallax never grew), the feature becomes a direction landmark: a unit direction
//   d_w with covariance Sigma_d, outside the state, observed as z = pi(R_w_c^T d_w) with
//   H_pose = d_uv_d_pc [[d_c]x, 0] (no translation: it constrains the orientation only) and noise
//   s^2 I + H_d Sigma_d H_d^T (its correlation with the pose is neglected).
// Map management as the stereo filter: a 4x4 image grid, up to new_per_zone_per_frame new
// initialisations per zone lacking landmarks, a bounded state and bounded candidate list,
// eviction of landmarks unseen for long when full, removal after repeated gating failures.
//
// Not thread-safe. Deterministic.

#include <deque>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "backend/ekf/ekf_map.h"
#include "backend/ekf/ekf_state.h"
#include "backend/estimator.h"
#include "backend/mono/mono_initializer.h"
#include "core/camera.h"

namespace dala {

struct MonoEkfOptions {
  int max_landmarks = 300;  // Bound of the EKF state.
  // Gaussian sum along the ray (published defaults of the authors' code: 0.5 m, 100 m).
  double d_min = 0.5;
  double d_max = 100.0;
  // sigma_i / s_i and the spacing in sigmas (not published; chosen: 4-sigma-wide coverage with
  // beta = 1.67, 12 hypotheses over 0.5..100 m).
  double alpha = 0.25;
  double k_sigma = 1.0;
  double prune_chi2 = 20.0;             // Hypothesis dropped above this squared Mahalanobis.
  double sprt_false_alarm = 0.01;       // a_FA.
  double sprt_missed_detection = 0.05;  // a_MD.
  double min_image_motion_chi2 = 8.0;   // Observation used only above this image motion.
  int pose_buffer_size = 100;           // Past poses kept for the replay (frames).
  int max_candidates = 150;             // Features being initialised at once.
  int infinity_after_frames = 40;       // Far hypothesis alive that long: point at infinity.
  int max_directions = 60;              // Direction landmarks (points at infinity) kept.
  // Map management (as StereoEkfOptions).
  int grid_cols = 4;
  int grid_rows = 4;
  int target_per_zone = 3;
  int new_per_zone_per_frame = 2;
  double gate_chi2 = 9.21;  // chi2 2 dof 99 %.
  int max_gate_failures = 3;
  int evict_unseen_frames = 10;
  double lost_rotation_sigma = 0.05;
  double lost_translation_sigma = 0.5;
  // Prediction model (file comment): "auto", "motion" or "constant_velocity".
  std::string prediction = "auto";
  // Constant-velocity model: velocity random walk, angular in rad s^-3/2, linear relative to the
  // initial speed |nu_0| in s^-1/2 (chosen: about the accelerations of a car or a walking
  // camera; not published).
  double cv_angular_acceleration_sigma = 0.5;
  double cv_linear_acceleration_sigma = 0.5;
  // The two-view start: pose sigmas (rad; units of the first baseline), landmarks per zone.
  double init_rotation_sigma = 0.002;
  double init_translation_sigma = 0.01;
  int init_per_zone = 6;
  // The two-view initialisation; System copies SystemOptions::ba.mono_init here (section
  // "mono_init" of the options, shared by both monocular estimators).
  MonoInitializerOptions mono_init;

  bool IsValid(std::string* why) const;
};

// The Gaussian-sum depths (s_i, sigma_i) of the options (file comment).
std::vector<std::pair<double, double>> GaussianSumDepths(const MonoEkfOptions& options);

struct MonoEkfFrameStats {
  int updated = 0;  // Observations applied in the EKF (points and directions).
  int gated_out = 0;
  int candidates = 0;  // Features being initialised after this frame.
  int hypotheses = 0;  // Alive hypotheses over all candidates.
  int inserted = 0;    // Landmarks inserted into the state this frame.
  int dropped = 0;     // Candidates with no hypothesis left.
  int directions = 0;  // Direction landmarks after this frame.
};

class MonoEkfEstimator : public Estimator {
 public:
  // Precondition (CHECK): the camera has no distortion (rectified pixels), valid options.
  MonoEkfEstimator(const PinholeCamera& camera, const MonoEkfOptions& options = {});

  std::string name() const override { return "ekf"; }
  std::string mode() const override { return "mono"; }
  EstimatorOutput Add(const FrameMeasurement& m) override;
  Trajectory trajectory() const override { return trajectory_; }
  std::vector<MapPoint> map() const override { return EkfMapPoints(state_, info_); }

  const EkfState& state() const { return state_; }
  Matrix6d pose_covariance() const { return state_.pose_covariance(); }
  const MonoEkfFrameStats& last_stats() const { return stats_; }
  bool IsCandidate(LandmarkId id) const { return candidates_.count(id) > 0; }
  bool IsDirection(LandmarkId id) const { return directions_.count(id) > 0; }
  // The model in use: "motion" or "constant_velocity" ("auto" until decided).
  std::string prediction() const;

 private:
  struct Hypothesis {
    double s = 0, sigma = 0;  // Initial depth along the first ray and its std.
    Eigen::Vector3d p_k;      // The point in the first camera, Kalman-updated by each used
    Eigen::Matrix3d cov_k;    // observation (for the scoring only), and its covariance.
    double log_likelihood = 0;
  };
  struct StoredObservation {
    int frame;
    Eigen::Vector2d uv;
    double sigma_px;
  };
  struct Candidate {
    int first_frame = 0;
    int last_used_frame = 0;
    int last_seen_frame = 0;
    Eigen::Vector2d last_used_uv;
    Eigen::Vector3d b_c;  // Unit ray in the first camera, and its covariance.
    Eigen::Matrix3d cov_b_c;
    Eigen::Vector3d d_w;                 // Unit ray in the world at the first observation.
    Eigen::Matrix3d cov_d_w;             // Its covariance (pixel noise and first-pose rotation).
    std::vector<Hypothesis> hypotheses;  // Ordered by depth; the last is the farthest.
    bool farthest_alive = true;
    std::vector<StoredObservation> observations;  // Used ones, the first included.
  };
  struct Direction {
    Eigen::Vector3d d_w;
    Eigen::Matrix3d cov;
    int last_seen = 0;
    int gate_failures = 0;
  };
  struct PoseRecord {
    Pose T_w_c;
    Matrix6d cov;
    Pose T_prev_cur = Pose::Identity();  // The motion input into this frame and its covariance.
    Matrix6d motion_cov = Matrix6d::Zero();
  };
  // Covariance of the right perturbation of T_c_j = T_w_c^-1 T_w_j (frame j relative to the
  // current frame c) from the motion inputs between them (updates ignored: conservative).
  Matrix6d RelativeCovariance(int j) const;

  void StartCandidate(const FeatureObservation& obs);
  // Scores the hypotheses with a new observation; returns false when the candidate is finished
  // (inserted, dropped or turned into a direction) and must be erased.
  bool UpdateCandidate(LandmarkId id, Candidate* c, const FeatureObservation& obs);
  // Refines the winner with the stored observations and augments the state; false when the
  // refined point disagrees with them (the candidate is then dropped).
  bool InsertLandmark(LandmarkId id, const Candidate& c, const Hypothesis& h);
  bool MakeRoom();

  enum class Prediction { kUndecided, kMotion, kConstantVelocity };
  // The constant-velocity model: before the two-view initialisation, and its start.
  EstimatorOutput AddBeforeInitialization(const FrameMeasurement& m);
  void StartFromTwoView(const MonoInitialization& init);
  void SwitchToConstantVelocity();
  Matrix6d VelocityNoise(double dt) const;  // Q_V dt.
  // After the prediction: the EKF update with the frame's observations and the removal of
  // unreliable landmarks; returns the landmarks per image zone. apply_updates false: the frame's
  // observations of state landmarks are not used (the two-view start, whose points come from
  // them).
  std::vector<int> UpdateState(const FrameMeasurement& m, bool apply_updates);
  // Then: the pose buffer (record of this frame), the candidates, new candidates, the stats and
  // the frame's pose in `out` and the trajectory.
  void ManageMap(const FrameMeasurement& m, const PoseRecord& record, std::vector<int> zone_count,
                 EstimatorOutput* out);

  PinholeCamera camera_;
  MonoEkfOptions options_;
  ImageGrid grid_;
  std::vector<std::pair<double, double>> depths_;
  EkfState state_;
  EkfLandmarkInfoMap info_;
  std::map<LandmarkId, Candidate> candidates_;  // Ordered: deterministic iteration.
  std::map<LandmarkId, Direction> directions_;
  std::unordered_set<LandmarkId> rejected_;
  std::map<int, PoseRecord> pose_buffer_;
  Trajectory trajectory_;
  int frame_index_ = -1;
  MonoEkfFrameStats stats_;
  Prediction prediction_ = Prediction::kUndecided;
  std::optional<MonoInitializer> initializer_;  // Constant velocity, before its start.
  double initial_speed_ = 0;                      // |nu_0| (map units per second).
  int64_t last_t_ns_ = 0;
  double last_dt_ = 0;
};

}  // namespace dala

#endif  // DALA_BACKEND_EKF_MONO_EKF_H_
