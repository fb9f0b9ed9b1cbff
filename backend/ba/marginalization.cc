#include "backend/ba/marginalization.h"

#include <ceres/dynamic_autodiff_cost_function.h>
#include <glog/logging.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <memory>

namespace dala {
namespace {

// Ceres's EigenQuaternionManifold Minus, y [-] x = to_delta(q_y * q_x^-1) with
// to_delta([w; u]) = u / |u| * atan2(|u|, w) (a half angle), and t_y - t_x; templated for autodiff.
// The sign of the quaternion is chosen with w >= 0 so that the result is continuous at 0.
template <typename T>
void PoseMinus(const T* y, const double* x, T* d) {
  const Eigen::Map<const Eigen::Quaternion<T>> q_y(y);
  const Eigen::Quaternion<T> q_x{T(x[3]), T(x[0]), T(x[1]), T(x[2])};
  Eigen::Quaternion<T> dq = q_y * q_x.conjugate();
  if (dq.w() < T(0.0)) dq.coeffs() = -dq.coeffs();
  const Eigen::Matrix<T, 3, 1> u = dq.vec();
  const T n2 = u.squaredNorm();
  if (n2 < T(1e-24)) {
    for (int i = 0; i < 3; ++i) d[i] = u[i] / dq.w();  // atan2(n, w) / n -> 1 / w.
  } else {
    using std::atan2;
    using std::sqrt;
    const T n = sqrt(n2);
    const T s = atan2(n, dq.w()) / n;
    for (int i = 0; i < 3; ++i) d[i] = u[i] * s;
  }
  for (int i = 0; i < 3; ++i) d[3 + i] = y[4 + i] - T(x[4 + i]);
}

struct PriorResidual {
  explicit PriorResidual(const MarginalizationPrior& prior) : prior_(prior) {}

  template <typename T>
  bool operator()(T const* const* blocks, T* residuals) const {
    const int n = static_cast<int>(prior_.keyframes.size());
    Eigen::Matrix<T, Eigen::Dynamic, 1> d(6 * n);
    for (int i = 0; i < n; ++i) PoseMinus(blocks[i], prior_.x_lin[i].data(), d.data() + 6 * i);
    for (int row = 0; row < prior_.rank(); ++row) {
      T acc = T(prior_.r0[row]);
      for (int col = 0; col < 6 * n; ++col) acc += T(prior_.sqrt_information(row, col)) * d[col];
      residuals[row] = acc;
    }
    return true;
  }

 private:
  MarginalizationPrior prior_;
};

// Pseudo-inverse of a symmetric PSD matrix, eigenvalues below floor * max (or 1e-12) zeroed.
Eigen::MatrixXd PseudoInverseSym(const Eigen::MatrixXd& H, double floor) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (H + H.transpose()));
  const Eigen::VectorXd& l = es.eigenvalues();
  const double threshold = std::max(1e-12, floor * std::max(0.0, l.maxCoeff()));
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(l.size());
  for (int i = 0; i < l.size(); ++i) {
    if (l[i] > threshold) inv[i] = 1.0 / l[i];
  }
  return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

}  // namespace

Vector6d PoseBlockMinus(const double* y, const double* x) {
  Vector6d d;
  PoseMinus(y, x, d.data());
  return d;
}

ceres::CostFunction* CreatePriorCost(const MarginalizationPrior& prior) {
  CHECK(!prior.empty()) << "CreatePriorCost called with an empty prior";
  CHECK_EQ(prior.keyframes.size(), prior.x_lin.size());
  CHECK_EQ(prior.sqrt_information.cols(), 6 * static_cast<int>(prior.keyframes.size()));
  CHECK_EQ(prior.sqrt_information.rows(), prior.r0.size());
  auto* cost = new ceres::DynamicAutoDiffCostFunction<PriorResidual, 4>(new PriorResidual(prior));
  for (size_t i = 0; i < prior.keyframes.size(); ++i) cost->AddParameterBlock(7);
  cost->SetNumResiduals(prior.rank());
  return cost;
}

MarginalizationPrior Marginalize(const MarginalizationInput& input) {
  // Column layout of the pose part: marginalised poses first, then the kept ones.
  std::map<const double*, int> pose_col;
  int num_pose_cols = 0;
  for (double* x : input.marginalized_poses) pose_col[x] = 6 * num_pose_cols++;
  const int num_marg_pose_cols = 6 * num_pose_cols;
  std::map<const double*, int> kept_index;
  for (size_t i = 0; i < input.kept_poses.size(); ++i) {
    pose_col[input.kept_poses[i].second] = 6 * num_pose_cols++;
    kept_index[input.kept_poses[i].second] = static_cast<int>(i);
  }
  const int P = 6 * num_pose_cols;
  std::map<const double*, int> landmark_index;
  for (size_t i = 0; i < input.marginalized_landmarks.size(); ++i) {
    landmark_index[input.marginalized_landmarks[i]] = static_cast<int>(i);
  }
  const int L = static_cast<int>(input.marginalized_landmarks.size());

  Eigen::MatrixXd H_pp = Eigen::MatrixXd::Zero(P, P);
  Eigen::VectorXd b_p = Eigen::VectorXd::Zero(P);
  std::vector<Eigen::Matrix3d> H_ll(L, Eigen::Matrix3d::Zero());
  std::vector<Eigen::MatrixXd> H_lp(L, Eigen::MatrixXd::Zero(3, P));
  std::vector<Eigen::Vector3d> b_l(L, Eigen::Vector3d::Zero());
  std::vector<bool> kept_connected(input.kept_poses.size(), false);

  auto manifold = MakePoseManifold();
  for (const FactorRef& f : input.factors) {
    CHECK(f.cost != nullptr);
    const auto& sizes = f.cost->parameter_block_sizes();
    CHECK_EQ(sizes.size(), f.blocks.size());
    const int m = f.cost->num_residuals();
    Eigen::VectorXd r(m);
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J_amb(
        sizes.size());
    std::vector<double*> jac_ptrs(sizes.size(), nullptr);
    for (size_t i = 0; i < sizes.size(); ++i) {
      const bool variable = pose_col.count(f.blocks[i]) || landmark_index.count(f.blocks[i]);
      if (variable) {
        J_amb[i].resize(m, sizes[i]);
        jac_ptrs[i] = J_amb[i].data();
      }
    }
    CHECK(f.cost->Evaluate(f.blocks.data(), r.data(), jac_ptrs.data()))
        << "a factor failed to evaluate during marginalisation";
    // IRLS weight of the robust loss.
    double w = 1.0;
    if (f.loss != nullptr) {
      double rho[3];
      f.loss->Evaluate(r.squaredNorm(), rho);
      w = std::sqrt(std::max(rho[1], 0.0));
    }
    r *= w;
    // Tangent-space Jacobians: poses J_amb * PlusJacobian (7x6), landmarks as they are.
    Eigen::MatrixXd J_pose = Eigen::MatrixXd::Zero(m, P);
    int landmark = -1;
    Eigen::MatrixXd J_land(m, 3);
    for (size_t i = 0; i < sizes.size(); ++i) {
      if (!jac_ptrs[i]) continue;
      const auto pit = pose_col.find(f.blocks[i]);
      if (pit != pose_col.end()) {
        CHECK_EQ(sizes[i], 7);
        Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jac;
        manifold->PlusJacobian(f.blocks[i], plus_jac.data());
        J_pose.middleCols(pit->second, 6) += w * J_amb[i] * plus_jac;
        const auto kit = kept_index.find(f.blocks[i]);
        if (kit != kept_index.end()) kept_connected[kit->second] = true;
      } else {
        CHECK_EQ(sizes[i], 3);
        CHECK_EQ(landmark, -1) << "a factor with two marginalised landmarks is not supported";
        landmark = landmark_index.at(f.blocks[i]);
        J_land = w * J_amb[i];
      }
    }
    H_pp.noalias() += J_pose.transpose() * J_pose;
    b_p.noalias() += J_pose.transpose() * r;
    if (landmark >= 0) {
      H_ll[landmark] += J_land.transpose() * J_land;
      H_lp[landmark].noalias() += J_land.transpose() * J_pose;
      b_l[landmark] += J_land.transpose() * r;
    }
  }

  // Step 1: eliminate the landmarks.
  for (int l = 0; l < L; ++l) {
    const Eigen::Matrix3d H_ll_inv = PseudoInverseSym(H_ll[l], input.eigenvalue_floor);
    const Eigen::MatrixXd tmp = H_lp[l].transpose() * H_ll_inv;  // P x 3.
    H_pp.noalias() -= tmp * H_lp[l];
    b_p.noalias() -= tmp * b_l[l];
  }
  // Step 2: eliminate the marginalised poses.
  const int K = P - num_marg_pose_cols;
  Eigen::MatrixXd H_k = H_pp.bottomRightCorner(K, K);
  Eigen::VectorXd b_k = b_p.tail(K);
  if (num_marg_pose_cols > 0) {
    const Eigen::MatrixXd H_mm_inv = PseudoInverseSym(
        H_pp.topLeftCorner(num_marg_pose_cols, num_marg_pose_cols), input.eigenvalue_floor);
    const Eigen::MatrixXd H_km = H_pp.bottomLeftCorner(K, num_marg_pose_cols);
    H_k.noalias() -= H_km * H_mm_inv * H_km.transpose();
    b_k.noalias() -= H_km * H_mm_inv * b_p.head(num_marg_pose_cols);
  }

  // Keep only the kept poses some factor connects.
  std::vector<int> cols;
  MarginalizationPrior prior;
  for (size_t i = 0; i < input.kept_poses.size(); ++i) {
    if (!kept_connected[i]) continue;
    prior.keyframes.push_back(input.kept_poses[i].first);
    PoseBlock x;
    std::copy(input.kept_poses[i].second, input.kept_poses[i].second + 7, x.begin());
    prior.x_lin.push_back(x);
    for (int c = 0; c < 6; ++c) cols.push_back(6 * static_cast<int>(i) + c);
  }
  if (cols.empty()) return prior;
  const int n = static_cast<int>(cols.size());
  Eigen::MatrixXd H(n, n);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    b[i] = b_k[cols[i]];
    for (int j = 0; j < n; ++j) H(i, j) = H_k(cols[i], cols[j]);
  }
  // Square root with an eigenvalue floor.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (H + H.transpose()));
  const Eigen::VectorXd& lambda = es.eigenvalues();
  const double threshold =
      std::max(1e-12, input.eigenvalue_floor * std::max(0.0, lambda.maxCoeff()));
  std::vector<int> keep;
  for (int i = 0; i < n; ++i) {
    if (lambda[i] > threshold) keep.push_back(i);
  }
  prior.sqrt_information.resize(static_cast<int>(keep.size()), n);
  prior.r0.resize(static_cast<int>(keep.size()));
  for (size_t k = 0; k < keep.size(); ++k) {
    const double l = lambda[keep[k]];
    const Eigen::VectorXd v = es.eigenvectors().col(keep[k]);
    prior.sqrt_information.row(static_cast<int>(k)) = std::sqrt(l) * v.transpose();
    prior.r0[static_cast<int>(k)] = v.dot(b) / std::sqrt(l);
  }
  return prior;
}

}  // namespace dala
