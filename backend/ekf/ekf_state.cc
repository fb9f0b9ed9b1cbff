#include "backend/ekf/ekf_state.h"

#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace dala {

EkfState::EkfState(int max_landmarks, bool with_velocity)
    : max_landmarks_(max_landmarks), landmark_offset_(with_velocity ? 12 : 6) {
  CHECK_GE(max_landmarks, 0);
  const int n = landmark_offset_ + 3 * max_landmarks;
  P_ = Eigen::MatrixXd::Zero(n, n);
}

void EkfState::Reset(const Pose& T_w_c, const Matrix6d& cov_pose) {
  T_w_c_ = T_w_c;
  ids_.clear();
  p_w_.clear();
  index_.clear();
  P_.setZero();
  // delta = Adj(T^-1) xi, so Cov(xi) = Adj(T) Cov(delta) Adj(T)^T.
  const Matrix6d A = AdjointSE3(T_w_c);
  P_.topLeftCorner<6, 6>() = A * cov_pose * A.transpose();
  w_.setZero();
}

void EkfState::Reset(const Pose& T_w_c, const Matrix6d& cov_pose, const Vector6d& w,
                     const Matrix6d& cov_w) {
  CHECK(has_velocity()) << "EkfState: Reset with a velocity needs with_velocity";
  Reset(T_w_c, cov_pose);
  w_ = w;
  P_.block<6, 6>(6, 6) = 0.5 * (cov_w + cov_w.transpose());
}

Matrix6d EkfState::velocity_covariance() const {
  CHECK(has_velocity());
  return P_.block<6, 6>(6, 6);
}

int EkfState::IndexOf(LandmarkId id) const {
  const auto it = index_.find(id);
  return it == index_.end() ? -1 : it->second;
}

Matrix6d EkfState::pose_covariance() const {
  const Matrix6d A = AdjointSE3(T_w_c_.inverse());
  return A * P_.topLeftCorner<6, 6>() * A.transpose();
}

Eigen::Matrix3d EkfState::landmark_covariance(int i) const {
  // p_w - p_hat = -[p_hat]x phi + e_i.
  const int o = landmark_offset_ + 3 * i;
  const Eigen::Matrix3d M = -Skew(p_w_[i]);
  const Eigen::Matrix3d cross = M * P_.block<3, 3>(0, o);
  return M * P_.topLeftCorner<3, 3>() * M.transpose() + cross + cross.transpose() +
         P_.block<3, 3>(o, o);
}

Eigen::MatrixXd EkfState::covariance() const {
  // C = J P J^T with J the map from e to the classic error: pose rows Adj(T^-1) (on xi),
  // velocity rows I (on e_w), landmark rows [-[p_hat_i]x (on phi), I (on e_i)].
  const int n = dim();
  const Matrix6d A = AdjointSE3(T_w_c_.inverse());
  auto apply_j = [&](const Eigen::MatrixXd& X) {
    Eigen::MatrixXd Y(n, X.cols());
    Y.topRows(6) = A * X.topRows(6);
    if (has_velocity()) Y.middleRows(6, 6) = X.middleRows(6, 6);
    for (int i = 0; i < num_landmarks(); ++i) {
      const int o = landmark_offset_ + 3 * i;
      Y.middleRows(o, 3) = X.middleRows(o, 3) - Skew(p_w_[i]) * X.topRows(3);
    }
    return Y;
  };
  const Eigen::MatrixXd JP = apply_j(P_.topLeftCorner(n, n));
  Eigen::MatrixXd C = apply_j(JP.transpose());
  return 0.5 * (C + C.transpose());
}

void EkfState::AddPoseNoise(const Matrix6d& Q_delta) {
  // G Q G^T as a rank update with B = G U sqrt(D), Q = U D U^T (Q is PSD: clamp round-off).
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 * (Q_delta + Q_delta.transpose()));
  const Matrix6d sqrt_Q =
      eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  const int n = dim();
  const Eigen::Matrix3d R = T_w_c_.linear();
  Eigen::MatrixXd B(n, 6);
  B.topRows(6) = AdjointSE3(T_w_c_) * sqrt_Q;
  if (has_velocity()) B.middleRows(6, 6).setZero();
  const Eigen::Matrix<double, 3, 6> sqrt_Q_phi = sqrt_Q.topRows(3);
  for (int i = 0; i < num_landmarks(); ++i) {
    B.middleRows(landmark_offset_ + 3 * i, 3) = Skew(p_w_[i]) * R * sqrt_Q_phi;
  }
  auto P = P_.topLeftCorner(n, n);
  P.selfadjointView<Eigen::Lower>().rankUpdate(B, 1.0);
  P.triangularView<Eigen::StrictlyUpper>() = P.transpose().eval();
}

void EkfState::Predict(const Pose& T_prev_cur, const Matrix6d& Q) {
  // F = I in the invariant error; the noise enters through G at the predicted estimate.
  T_w_c_ = Orthonormalized(T_w_c_ * T_prev_cur);
  AddPoseNoise(Q);
}

void EkfState::InflatePose(const Matrix6d& Q) { AddPoseNoise(Q); }

void EkfState::PredictConstantVelocity(double dt, const Matrix6d& Q_V) {
  CHECK(has_velocity()) << "EkfState: constant-velocity prediction needs with_velocity";
  CHECK_GT(dt, 0.0);
  const Vector6d step = w_ * dt;
  T_w_c_ = Orthonormalized(T_w_c_ * ExpSE3(step));
  const Matrix6d J = RightJacobianSE3(step) * dt;  // d (body increment) / d w.
  const int n = dim();
  // X (file comment): rows of the pose and the landmarks, zero on the velocity rows.
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(n, 6);
  X.topRows(6) = AdjointSE3(T_w_c_) * J;
  const Eigen::Matrix<double, 3, 6> R_J_phi = T_w_c_.linear() * J.topRows(3);
  for (int i = 0; i < num_landmarks(); ++i) {
    X.middleRows(landmark_offset_ + 3 * i, 3) = Skew(p_w_[i]) * R_J_phi;
  }
  auto P = P_.topLeftCorner(n, n);
  const Eigen::MatrixXd P_w = P.middleCols(6, 6);  // A copy: P changes below.
  const Matrix6d P_ww = P_w.middleRows(6, 6);
  Eigen::MatrixXd B = X;
  B.middleRows(6, 6) = Matrix6d::Identity();
  const Eigen::MatrixXd XP = X * P_w.transpose();
  P += XP + XP.transpose();
  P.noalias() += X * P_ww * X.transpose();
  P.noalias() += B * Q_V * B.transpose();
  P = (0.5 * (P + P.transpose())).eval();
}

int EkfState::AddLandmarkFromCamera(LandmarkId id, const Eigen::Vector3d& p_c,
                                    const Eigen::Matrix3d& cov_p_c) {
  const Eigen::Matrix3d R = T_w_c_.linear();
  Eigen::Matrix<double, 3, 6> J_xi;  // e_new = rho + R dp_c.
  J_xi << Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Identity();
  return AddInvariantLandmark(id, T_w_c_ * p_c, R * cov_p_c * R.transpose(), J_xi);
}

int EkfState::AddLandmark(LandmarkId id, const Eigen::Vector3d& p_w, const Eigen::Matrix3d& cov_p_w,
                          const Eigen::Matrix<double, 3, 6>& J_pose) {
  // e_new = (p_w - p_hat) + [p_hat]x phi = J_pose Adj(T^-1) xi + [p_hat]x phi + noise.
  Eigen::Matrix<double, 3, 6> J_xi = J_pose * AdjointSE3(T_w_c_.inverse());
  J_xi.leftCols<3>() += Skew(p_w);
  return AddInvariantLandmark(id, p_w, cov_p_w, J_xi);
}

int EkfState::AddInvariantLandmark(LandmarkId id, const Eigen::Vector3d& p_w,
                                   const Eigen::Matrix3d& cov_p_w,
                                   const Eigen::Matrix<double, 3, 6>& J_xi) {
  CHECK(!full()) << "EkfState: the state is full (" << max_landmarks_ << " landmarks)";
  CHECK_EQ(IndexOf(id), -1) << "EkfState: landmark " << id << " is already in the state";
  const int n = dim();
  // Cross-covariance with everything: J_xi * P(pose rows, all columns).
  const Eigen::MatrixXd P_lx = J_xi * P_.topLeftCorner(6, n);
  Eigen::Matrix3d P_ll = J_xi * P_.topLeftCorner<6, 6>() * J_xi.transpose() + cov_p_w;
  P_ll = 0.5 * (P_ll + P_ll.transpose()).eval();
  P_.block(n, 0, 3, n) = P_lx;
  P_.block(0, n, n, 3) = P_lx.transpose();
  P_.block<3, 3>(n, n) = P_ll;
  const int index = num_landmarks();
  ids_.push_back(id);
  p_w_.push_back(p_w);
  index_[id] = index;
  return index;
}

void EkfState::RemoveLandmarks(const std::vector<bool>& remove) {
  CHECK_EQ(static_cast<int>(remove.size()), num_landmarks());
  const int n = dim();
  // Kept state coordinates, in order.
  std::vector<int> keep;
  keep.reserve(n);
  for (int k = 0; k < landmark_offset_; ++k) keep.push_back(k);
  std::vector<LandmarkId> ids;
  std::vector<Eigen::Vector3d> p_w;
  for (int i = 0; i < num_landmarks(); ++i) {
    if (remove[i]) continue;
    for (int k = 0; k < 3; ++k) keep.push_back(landmark_offset_ + 3 * i + k);
    ids.push_back(ids_[i]);
    p_w.push_back(p_w_[i]);
  }
  const int m = static_cast<int>(keep.size());
  if (m == n) return;
  // In-place compaction: keep[] is increasing, so moving entries towards the top-left never
  // overwrites an entry still to be read.
  for (int c = 0; c < m; ++c) {
    for (int r = 0; r < m; ++r) P_(r, c) = P_(keep[r], keep[c]);
  }
  P_.block(m, 0, n - m, n).setZero();
  P_.block(0, m, m, n - m).setZero();
  ids_ = std::move(ids);
  p_w_ = std::move(p_w);
  index_.clear();
  for (int i = 0; i < num_landmarks(); ++i) index_[ids_[i]] = i;
}

Eigen::MatrixXd EkfState::InvariantHPose(const EkfUpdateBlock& b) const {
  Eigen::MatrixXd H = b.H_pose * AdjointSE3(T_w_c_.inverse());
  if (b.landmark >= 0) H.leftCols(3) -= b.H_landmark * Skew(p_w_[b.landmark]);
  return H;
}

Eigen::MatrixXd EkfState::InnovationCovariance(const EkfUpdateBlock& b) const {
  const int l = b.landmark;
  const Eigen::MatrixXd H_xi = InvariantHPose(b);
  Eigen::MatrixXd S = H_xi * P_.topLeftCorner<6, 6>() * H_xi.transpose() + b.R;
  if (l >= 0) {
    const int o = landmark_offset_ + 3 * l;
    const Eigen::MatrixXd cross = H_xi * P_.block(0, o, 6, 3) * b.H_landmark.transpose();
    S += cross + cross.transpose() + b.H_landmark * P_.block<3, 3>(o, o) * b.H_landmark.transpose();
  }
  return S;
}

bool EkfState::Update(const std::vector<EkfUpdateBlock>& blocks) {
  if (blocks.empty()) return true;
  const int n = dim();
  int m = 0;
  for (const EkfUpdateBlock& b : blocks) {
    CHECK_EQ(b.H_pose.rows(), b.residual.size());
    CHECK(b.landmark < num_landmarks());
    m += static_cast<int>(b.residual.size());
  }
  // W = P H^T (n x m), built from the few non-zero columns of H (invariant coordinates).
  Eigen::MatrixXd W(n, m);
  Eigen::VectorXd r(m);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(m, m);
  std::vector<Eigen::MatrixXd> H_xi;
  H_xi.reserve(blocks.size());
  int row = 0;
  for (const EkfUpdateBlock& b : blocks) {
    const int k = static_cast<int>(b.residual.size());
    H_xi.push_back(InvariantHPose(b));
    W.middleCols(row, k) = P_.topLeftCorner(n, 6) * H_xi.back().transpose();
    if (b.landmark >= 0) {
      W.middleCols(row, k) +=
          P_.block(0, landmark_offset_ + 3 * b.landmark, n, 3) * b.H_landmark.transpose();
    }
    r.segment(row, k) = b.residual;
    R.block(row, row, k, k) = b.R;
    row += k;
  }
  // S = H W + R.
  Eigen::MatrixXd S = R;
  row = 0;
  for (size_t j = 0; j < blocks.size(); ++j) {
    const EkfUpdateBlock& b = blocks[j];
    const int k = static_cast<int>(b.residual.size());
    S.middleRows(row, k) += H_xi[j] * W.topRows(6);
    if (b.landmark >= 0) {
      S.middleRows(row, k) += b.H_landmark * W.middleRows(landmark_offset_ + 3 * b.landmark, 3);
    }
    row += k;
  }
  S = 0.5 * (S + S.transpose()).eval();
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return false;
  // V = W L^-T, so that W S^-1 W^T = V V^T and K r = V (L^-1 r).
  const Eigen::MatrixXd V = llt.matrixL().solve(W.transpose()).transpose();
  const Eigen::VectorXd dx = V * llt.matrixL().solve(r);
  auto P = P_.topLeftCorner(n, n);
  P.selfadjointView<Eigen::Lower>().rankUpdate(V, -1.0);
  P.triangularView<Eigen::StrictlyUpper>() = P.transpose().eval();
  // Injection on SE_{1+N}(3): T <- Exp(xi) T, p_i <- Exp(phi) p_i + J_l(phi) e_i; w <- w + e_w.
  const Vector6d xi = dx.head<6>();
  T_w_c_ = Orthonormalized(ExpSE3(xi) * T_w_c_);
  const Eigen::Matrix3d R_phi = ExpSO3(xi.head<3>());
  const Eigen::Matrix3d J_l = LeftJacobianSO3(xi.head<3>());
  if (has_velocity()) w_ += dx.segment<6>(6);
  for (int i = 0; i < num_landmarks(); ++i) {
    p_w_[i] = R_phi * p_w_[i] + J_l * dx.segment<3>(landmark_offset_ + 3 * i);
  }
  return true;
}

}  // namespace dala
