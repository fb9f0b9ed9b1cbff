#ifndef DALA_BACKEND_EKF_EKF_STATE_H_
#define DALA_BACKEND_EKF_EKF_STATE_H_

// EkfState: the joint state of an EKF-SLAM filter and the only code that modifies its covariance
// (as OpenVINS keeps its covariance behind StateHelper). Used by StereoEkfEstimator and
// MonoEkfEstimator.
//
// State: x = (T_w_c, p_w_1 .. p_w_N), the camera pose in the world and Euclidean landmarks.
//
// Error state: the right-invariant error of the group SE_{1+N}(3) (Barrau & Bonnabel, "An
// EKF-SLAM algorithm with consistency properties", 2015), in the world frame:
//   T_w_c = Exp(xi) T_hat,   xi = [phi; rho]               (left perturbation, core/geometry.h),
//   p_w_i = Exp(phi) p_hat_i + J_l(phi) e_i  ~= p_hat_i + phi x p_hat_i + e_i,
//   e = [phi; rho; e_1; ...; e_N],  P = Cov(e), (6 + 3N) x (6 + 3N)   (stored internally).
// Why: the 6 unobservable directions of SLAM (a global rotation dtheta and translation dt of the
// whole scene) are, in these coordinates, N = [phi = dtheta, rho = 0, e_i = 0] and
// [0, dt, dt, ..., dt], independent of the estimate. The observation Jacobians below are exactly
// zero along N at ANY linearisation point, and the prediction keeps N, so the filter never gains
// information along them. With the classic error (pose on the right, landmarks additive) the
// unobservable subspace depends on (R_hat, t_hat, p_hat); linearising at successive, different
// estimates gains spurious information on the global orientation: the classic EKF-SLAM
// overconfidence (Huang et al.), measured in docs/ekf.md (pose NEES).
//
// The API speaks the classic coordinates everywhere (pose covariances for the right perturbation
// T_hat Exp(delta), landmark errors additive, observation Jacobians d h / d delta and
// d h / d p_w); this class converts at its boundary. With delta = Adj(T_hat^-1) xi and
// p_w - p_hat = -[p_hat]x phi + e_i:
//   H_xi = H_delta Adj(T_hat^-1) - H_p [p_hat]x [I 0],   H_e = H_p.
// For an observation of p_c = R^T (p_w - t): H_xi = [0, -D R^T], H_e = D R^T (D = d h / d p_c),
// whose phi part is zero at any estimate.
//
// Prediction with a relative motion M = T_prev_cur = M_hat Exp(eta), eta ~ N(0, Q):
//   T_cur = Exp(xi) T_hat_prev M_hat Exp(eta) ~= Exp(xi + Adj(T_hat_cur) eta) T_hat_cur,
//   and the landmark errors, defined relative to phi, take the rotation noise:
//   e_i <- e_i + [p_hat_i]x R_hat_cur eta_phi.   So F = I and
//   G = [Adj(T_hat_cur); [p_hat_1]x R_hat_cur, 0; ...] (the adjoint of SE_{1+N}(3), pose columns),
//   P <- P + G Q G^T (O(N^2), a rank-6 update).
//
// Update: stacked observation blocks (each touches the pose and at most one landmark), batched:
//   W = P H^T, S = H W + R = L L^T, K = W S^-1, e_hat = K r,
//   P <- P - W S^-1 W^T = P - V V^T with V = W L^-T   (a symmetric rank update: P stays symmetric
//   by construction and is re-symmetrised; this equals the Joseph form for the optimal gain).
//   Injection: T_hat <- Exp(xi_hat) T_hat, p_hat_i <- Exp(phi_hat) p_hat_i + J_l(phi_hat) e_hat_i
//   (the covariance reset Jacobian ~= I is neglected, as usual for small corrections).
//
// Landmark augmentation from a point p_c measured in the current camera frame with covariance
// C (independent of the state): p_w = R p_c + t gives e_new = rho + R_hat dp_c, so
//   P_ll = P_rho,rho + R C R^T,  P_l,x = P_rho,x   (full cross-covariance).
//
// Optional velocity (EkfState(max, /*with_velocity=*/true), the mono EKF's constant-velocity
// model): x = (T_w_c, w, p_w_1 .. p_w_N) with w = [omega; nu] the camera's twist in its own frame,
// per second: over dt the camera moves by T_prev_cur = Exp(w dt) (core/geometry.h ExpSE3).
// Its error is additive, w = w_hat + e_w, e = [phi; rho; e_w; e_1; ...] (dimension 12 + 3N). A
// body-frame twist does not change under a global rotation/translation of the scene, so the
// unobservable directions above stay [phi = dtheta, e_w = 0, ...] and [0, dt, e_w = 0, dt, ...]:
// the consistency argument holds unchanged. Observations never involve w (zero columns); it is
// corrected through its correlation with the pose.
// Constant-velocity prediction with a velocity impulse V ~ N(0, Q_V) (an acceleration random
// walk, MonoSLAM): w_cur = w + V, T_cur = T_prev Exp((w + V) dt). With M_hat = Exp(w_hat dt)
// and J = J_r(w_hat dt) dt (RightJacobianSE3), Exp((w + V) dt) ~= M_hat Exp(J (e_w + V)), so the
// pose takes the body increment u = J (e_w + V) like a motion noise above:
//   xi <- xi + Adj(T_hat_cur) u,   e_i <- e_i + [p_hat_i]x R_hat_cur u_phi,   e_w <- e_w + V,
// i.e. e <- A e + B V with A = I + X S_w (S_w selects e_w), B = X + [0; I; 0],
//   X = [Adj(T_hat_cur) J; 0; [p_hat_1]x R_hat_cur J_phi; ...]   (J_phi: the rotation rows of J),
//   P <- A P A^T + B Q_V B^T = P + X P_w^T + P_w X^T + X P_ww X^T + B Q_V B^T  (P_w = P S_w^T).

#include <Eigen/Core>
#include <unordered_map>
#include <vector>

#include "core/geometry.h"
#include "core/types.h"

namespace dala {

// One observation block for EkfState::Update: residual r = z - h(x_hat) of dimension k,
// r ~= H_pose delta + H_landmark dp_landmark + noise(R), in the classic coordinates
// (T_w_c = T_hat Exp(delta), p_w = p_hat + dp; EkfState converts).
struct EkfUpdateBlock {
  Eigen::VectorXd residual;
  Eigen::MatrixXd R;
  Eigen::Matrix<double, Eigen::Dynamic, 6> H_pose;
  int landmark = -1;  // State index of the landmark, or -1 for a pose-only observation.
  Eigen::Matrix<double, Eigen::Dynamic, 3> H_landmark;
};

class EkfState {
 public:
  // max_landmarks bounds the state (storage is allocated once: (6+3N)^2 doubles, (12+3N)^2 with
  // the velocity).
  explicit EkfState(int max_landmarks, bool with_velocity = false);

  // cov_pose: of the right perturbation delta (T_w_c = T_hat Exp(delta)). With the velocity:
  // it is set to zero with zero covariance (use the overload).
  void Reset(const Pose& T_w_c, const Matrix6d& cov_pose);
  // With the velocity (CHECK): w and its covariance (uncorrelated with the pose).
  void Reset(const Pose& T_w_c, const Matrix6d& cov_pose, const Vector6d& w,
             const Matrix6d& cov_w);

  const Pose& T_w_c() const { return T_w_c_; }
  // Covariance of delta in T_w_c = T_hat Exp(delta).
  Matrix6d pose_covariance() const;
  int num_landmarks() const { return static_cast<int>(ids_.size()); }
  int max_landmarks() const { return max_landmarks_; }
  bool full() const { return num_landmarks() >= max_landmarks_; }
  int dim() const { return landmark_offset_ + 3 * num_landmarks(); }
  bool has_velocity() const { return landmark_offset_ > 6; }
  // The twist [omega; nu] per second in the camera frame, and its covariance (with_velocity).
  const Vector6d& velocity() const { return w_; }
  Matrix6d velocity_covariance() const;
  // State index of a landmark id, -1 when not in the state.
  int IndexOf(LandmarkId id) const;
  LandmarkId id(int i) const { return ids_[i]; }
  const Eigen::Vector3d& p_w(int i) const { return p_w_[i]; }
  // Covariance of p_w_i - p_hat_i.
  Eigen::Matrix3d landmark_covariance(int i) const;
  // The full covariance in the classic coordinates [delta; (e_w;) p_w_1 - p_hat_1; ...] (a copy,
  // O(N^2)).
  Eigen::MatrixXd covariance() const;
  // The stored covariance of the invariant error e (file comment).
  Eigen::Block<const Eigen::MatrixXd> invariant_covariance() const {
    return P_.topLeftCorner(dim(), dim());
  }

  // T_w_c <- T_w_c * T_prev_cur; Q is the covariance of eta in T_prev_cur = M_hat Exp(eta).
  void Predict(const Pose& T_prev_cur, const Matrix6d& Q);
  // Adds Q to the covariance of delta (T_w_c = T_hat Exp(delta)): the pose is kept, no motion
  // known. Correlations are updated as for a prediction with the identity motion.
  void InflatePose(const Matrix6d& Q);
  // Constant-velocity prediction over dt seconds (file comment); Q_V is the covariance of the
  // velocity impulse V of this step. CHECKs has_velocity().
  void PredictConstantVelocity(double dt, const Matrix6d& Q_V);

  // Appends a landmark from p_c (current camera frame, covariance cov_p_c). CHECKs not full and
  // id not present. Returns its index.
  int AddLandmarkFromCamera(LandmarkId id, const Eigen::Vector3d& p_c,
                            const Eigen::Matrix3d& cov_p_c);
  // Appends a landmark given in the world with cov_p_w, uncorrelated with the state except
  // through J_pose (d p_w / d delta of the current pose, classic right perturbation; zero for
  // none).
  int AddLandmark(LandmarkId id, const Eigen::Vector3d& p_w, const Eigen::Matrix3d& cov_p_w,
                  const Eigen::Matrix<double, 3, 6>& J_pose);

  // Removes the landmarks whose flag is true (size num_landmarks()); order of the others kept.
  void RemoveLandmarks(const std::vector<bool>& remove);

  // Batched EKF update (file comment). Returns false (state untouched) when S is not positive
  // definite.
  bool Update(const std::vector<EkfUpdateBlock>& blocks);

  // Innovation covariance H P H^T + R of one block (for gating).
  Eigen::MatrixXd InnovationCovariance(const EkfUpdateBlock& block) const;

 private:
  int AddInvariantLandmark(LandmarkId id, const Eigen::Vector3d& p_w,
                           const Eigen::Matrix3d& cov_p_w, const Eigen::Matrix<double, 3, 6>& J_xi);
  // H_pose of a classic block (d h / d delta, d h / d p_w) converted to d h / d xi.
  Eigen::MatrixXd InvariantHPose(const EkfUpdateBlock& block) const;
  // P <- P + G Q G^T with G of the prediction (file comment) at the current estimate.
  void AddPoseNoise(const Matrix6d& Q_delta);

  int max_landmarks_;
  int landmark_offset_;  // 6, or 12 with the velocity: index of the first landmark's error.
  Pose T_w_c_ = Pose::Identity();
  Vector6d w_ = Vector6d::Zero();
  std::vector<LandmarkId> ids_;
  std::vector<Eigen::Vector3d> p_w_;
  std::unordered_map<LandmarkId, int> index_;
  Eigen::MatrixXd P_;  // (offset + 3 max) square storage; the top-left dim() block is the covariance.
};

}  // namespace dala

#endif  // DALA_BACKEND_EKF_EKF_STATE_H_
