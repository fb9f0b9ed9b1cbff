#ifndef DALA_BACKEND_EKF_EKF_STATE_H_
#define DALA_BACKEND_EKF_EKF_STATE_H_

// EkfState: the joint state of an EKF-SLAM filter and the only code that modifies its covariance
// (as OpenVINS keeps its covariance behind StateHelper). Used by StereoEkfEstimator and
// MonoEkfEstimator.
//
// State and error state (stated once here for both filters):
//   x = (T_w_c, p_w_1 .. p_w_N)      camera pose in the world, Euclidean landmarks in the world.
//   Pose error on the right:  T_w_c = T_hat * Exp(delta),  delta = [phi; rho]  (core/geometry.h).
//   Landmark error additive:  p_w_i = p_hat_i + dp_i.
//   Error vector e = [delta (6); dp_1 (3); ...; dp_N (3)],  P = Cov(e), (6 + 3N) x (6 + 3N).
//
// Prediction with a relative motion M = T_prev_cur = M_hat * Exp(eta), eta ~ N(0, Q):
//   T_cur = T_prev * M = T_hat_prev Exp(delta_prev) M_hat Exp(eta)
//         = T_hat_prev M_hat Exp(Adj(M_hat^-1) delta_prev) Exp(eta)
//        ~= T_hat_cur Exp(Adj(M_hat^-1) delta_prev + eta),
//   so F = d delta_cur / d delta_prev = Adj(M_hat^-1), G = I, landmarks unchanged:
//   P_pp <- F P_pp F^T + Q,  P_pl <- F P_pl.
//
// Update: stacked observation blocks (each touches the pose and at most one landmark), batched:
//   W = P H^T, S = H W + R = L L^T, K = W S^-1, e_hat = K r,
//   P <- P - W S^-1 W^T = P - V V^T with V = W L^-T   (a symmetric rank update: P stays symmetric
//   by construction and is re-symmetrised; this equals the Joseph form for the optimal gain).
//   The correction is injected as T_hat <- T_hat Exp(e_hat_pose), p_hat_i <- p_hat_i + e_hat_i
//   (the reset Jacobian Jr^-1(e_hat) ~= I is neglected, as usual for small corrections).
//
// Landmark augmentation from a point p_c measured in the current camera frame with covariance
// C (independent of the state): p_w = T_w_c p_c = R (p_c + phi x p_c + rho) to first order, so
//   J_pose = [-R [p_c]x, R],  J_pc = R,
//   P_ll = J_pose P_pp J_pose^T + R C R^T,  P_lx = J_pose P_px  (full cross-covariance).

#include <Eigen/Core>
#include <unordered_map>
#include <vector>

#include "core/geometry.h"
#include "core/types.h"

namespace dala {

// One observation block for EkfState::Update: residual r = z - h(x_hat) of dimension k,
// r ~= H_pose delta + H_landmark dp_landmark + noise(R).
struct EkfUpdateBlock {
  Eigen::VectorXd residual;
  Eigen::MatrixXd R;
  Eigen::Matrix<double, Eigen::Dynamic, 6> H_pose;
  int landmark = -1;  // State index of the landmark, or -1 for a pose-only observation.
  Eigen::Matrix<double, Eigen::Dynamic, 3> H_landmark;
};

class EkfState {
 public:
  // max_landmarks bounds the state (storage is allocated once: (6+3N)^2 doubles).
  explicit EkfState(int max_landmarks);

  void Reset(const Pose& T_w_c, const Matrix6d& cov_pose);

  const Pose& T_w_c() const { return T_w_c_; }
  Matrix6d pose_covariance() const { return P_.topLeftCorner<6, 6>(); }
  int num_landmarks() const { return static_cast<int>(ids_.size()); }
  int max_landmarks() const { return max_landmarks_; }
  bool full() const { return num_landmarks() >= max_landmarks_; }
  int dim() const { return 6 + 3 * num_landmarks(); }
  // State index of a landmark id, -1 when not in the state.
  int IndexOf(LandmarkId id) const;
  LandmarkId id(int i) const { return ids_[i]; }
  const Eigen::Vector3d& p_w(int i) const { return p_w_[i]; }
  Eigen::Matrix3d landmark_covariance(int i) const { return P_.block<3, 3>(6 + 3 * i, 6 + 3 * i); }
  // The full covariance (dim x dim block of the storage).
  Eigen::Block<const Eigen::MatrixXd> covariance() const { return P_.topLeftCorner(dim(), dim()); }

  // T_w_c <- T_w_c * T_prev_cur, covariance as in the file comment.
  void Predict(const Pose& T_prev_cur, const Matrix6d& Q);
  // Adds Q to the pose covariance (no motion known).
  void InflatePose(const Matrix6d& Q);

  // Appends a landmark from p_c (current camera frame, covariance cov_p_c). CHECKs not full and
  // id not present. Returns its index.
  int AddLandmarkFromCamera(LandmarkId id, const Eigen::Vector3d& p_c,
                            const Eigen::Matrix3d& cov_p_c);
  // Appends a landmark given in the world with cov_p_w, uncorrelated with the state except
  // through J_pose (d p_w / d delta of the current pose; zero for none).
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
  int max_landmarks_;
  Pose T_w_c_ = Pose::Identity();
  std::vector<LandmarkId> ids_;
  std::vector<Eigen::Vector3d> p_w_;
  std::unordered_map<LandmarkId, int> index_;
  Eigen::MatrixXd P_;  // (6 + 3 max) square storage; the top-left dim() block is the covariance.
};

}  // namespace dala

#endif  // DALA_BACKEND_EKF_EKF_STATE_H_
