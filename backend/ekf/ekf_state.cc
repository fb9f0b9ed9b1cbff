#include "backend/ekf/ekf_state.h"

#include <glog/logging.h>

#include <Eigen/Cholesky>

namespace dala {

EkfState::EkfState(int max_landmarks) : max_landmarks_(max_landmarks) {
  CHECK_GE(max_landmarks, 0);
  const int n = 6 + 3 * max_landmarks;
  P_ = Eigen::MatrixXd::Zero(n, n);
}

void EkfState::Reset(const Pose& T_w_c, const Matrix6d& cov_pose) {
  T_w_c_ = T_w_c;
  ids_.clear();
  p_w_.clear();
  index_.clear();
  P_.setZero();
  P_.topLeftCorner<6, 6>() = cov_pose;
}

int EkfState::IndexOf(LandmarkId id) const {
  const auto it = index_.find(id);
  return it == index_.end() ? -1 : it->second;
}

void EkfState::Predict(const Pose& T_prev_cur, const Matrix6d& Q) {
  const int n = dim();
  const Matrix6d F = AdjointSE3(T_prev_cur.inverse());
  T_w_c_ = Orthonormalized(T_w_c_ * T_prev_cur);
  const Matrix6d P_pp = F * P_.topLeftCorner<6, 6>() * F.transpose() + Q;
  P_.topLeftCorner<6, 6>() = 0.5 * (P_pp + P_pp.transpose());
  if (n > 6) {
    const Eigen::MatrixXd P_pl = F * P_.block(0, 6, 6, n - 6);
    P_.block(0, 6, 6, n - 6) = P_pl;
    P_.block(6, 0, n - 6, 6) = P_pl.transpose();
  }
}

void EkfState::InflatePose(const Matrix6d& Q) { P_.topLeftCorner<6, 6>() += Q; }

int EkfState::AddLandmarkFromCamera(LandmarkId id, const Eigen::Vector3d& p_c,
                                    const Eigen::Matrix3d& cov_p_c) {
  const Eigen::Matrix3d R = T_w_c_.linear();
  Eigen::Matrix<double, 3, 6> J_pose;
  J_pose << -R * Skew(p_c), R;
  return AddLandmark(id, T_w_c_ * p_c, R * cov_p_c * R.transpose(), J_pose);
}

int EkfState::AddLandmark(LandmarkId id, const Eigen::Vector3d& p_w, const Eigen::Matrix3d& cov_p_w,
                          const Eigen::Matrix<double, 3, 6>& J_pose) {
  CHECK(!full()) << "EkfState: the state is full (" << max_landmarks_ << " landmarks)";
  CHECK_EQ(IndexOf(id), -1) << "EkfState: landmark " << id << " is already in the state";
  const int n = dim();
  // Cross-covariance with everything: J_pose * P(pose rows, all columns).
  const Eigen::MatrixXd P_lx = J_pose * P_.topLeftCorner(6, n);
  Eigen::Matrix3d P_ll = J_pose * P_.topLeftCorner<6, 6>() * J_pose.transpose() + cov_p_w;
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
  for (int k = 0; k < 6; ++k) keep.push_back(k);
  std::vector<LandmarkId> ids;
  std::vector<Eigen::Vector3d> p_w;
  for (int i = 0; i < num_landmarks(); ++i) {
    if (remove[i]) continue;
    for (int k = 0; k < 3; ++k) keep.push_back(6 + 3 * i + k);
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

Eigen::MatrixXd EkfState::InnovationCovariance(const EkfUpdateBlock& b) const {
  const int l = b.landmark;
  Eigen::MatrixXd S = b.H_pose * P_.topLeftCorner<6, 6>() * b.H_pose.transpose() + b.R;
  if (l >= 0) {
    const int o = 6 + 3 * l;
    const Eigen::MatrixXd cross = b.H_pose * P_.block(0, o, 6, 3) * b.H_landmark.transpose();
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
  // W = P H^T (n x m), built from the few non-zero columns of H.
  Eigen::MatrixXd W(n, m);
  Eigen::VectorXd r(m);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(m, m);
  int row = 0;
  for (const EkfUpdateBlock& b : blocks) {
    const int k = static_cast<int>(b.residual.size());
    W.middleCols(row, k) = P_.topLeftCorner(n, 6) * b.H_pose.transpose();
    if (b.landmark >= 0) {
      W.middleCols(row, k) += P_.block(0, 6 + 3 * b.landmark, n, 3) * b.H_landmark.transpose();
    }
    r.segment(row, k) = b.residual;
    R.block(row, row, k, k) = b.R;
    row += k;
  }
  // S = H W + R.
  Eigen::MatrixXd S = R;
  row = 0;
  for (const EkfUpdateBlock& b : blocks) {
    const int k = static_cast<int>(b.residual.size());
    S.middleRows(row, k) += b.H_pose * W.topRows(6);
    if (b.landmark >= 0) S.middleRows(row, k) += b.H_landmark * W.middleRows(6 + 3 * b.landmark, 3);
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
  T_w_c_ = Orthonormalized(T_w_c_ * ExpSE3(dx.head<6>()));
  for (int i = 0; i < num_landmarks(); ++i) p_w_[i] += dx.segment<3>(6 + 3 * i);
  return true;
}

}  // namespace dala
