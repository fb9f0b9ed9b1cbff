#include "backend/ba/pose_only.h"

#include <ceres/crs_matrix.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "backend/ba/pose_block.h"
#include "backend/ba/reprojection_factors.h"
#include "backend/ba/solver_time.h"

namespace dala {

bool PoseOnlyOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(loss_scale > 0.0)) return fail("loss_scale must be > 0");
  if (max_num_iterations < 1) return fail("max_num_iterations must be >= 1");
  if (!(max_solver_time_in_seconds >= 0.0)) {
    return fail("max_solver_time_in_seconds must be >= 0 (0: no time limit)");
  }
  if (max_outlier_rounds < 0) return fail("max_outlier_rounds must be >= 0");
  if (min_inliers < 3) return fail("min_inliers must be >= 3 (a pose has 6 dof)");
  if (num_threads < 1) return fail("num_threads must be >= 1");
  return true;
}

const char* PoseOnlyStatusName(PoseOnlyStatus s) {
  switch (s) {
    case PoseOnlyStatus::kOk:
      return "ok";
    case PoseOnlyStatus::kTooFewObservations:
      return "too_few_observations";
    case PoseOnlyStatus::kDegenerate:
      return "degenerate";
    case PoseOnlyStatus::kSolverFailed:
      return "solver_failed";
  }
  return "?";
}

PoseOnlyResult EstimatePoseOnly(const StereoIntrinsics& K,
                                const std::vector<BaObservation>& observations,
                                const LandmarkLookup& p_w_of, const Pose& T_w_c_guess,
                                const PoseOnlyOptions& options) {
  std::string why;
  CHECK(options.IsValid(&why)) << "invalid PoseOnlyOptions: " << why;
  CHECK(K.IsValid(&why)) << "invalid StereoIntrinsics: " << why;

  PoseOnlyResult result;
  result.T_w_c = T_w_c_guess;
  const int n = static_cast<int>(observations.size());
  result.inliers.assign(n, false);
  std::vector<Eigen::Vector3d> p_w(n, Eigen::Vector3d::Zero());
  for (int i = 0; i < n; ++i) {
    if (auto p = p_w_of(observations[i].landmark)) {
      p_w[i] = *p;
      result.inliers[i] = true;
    }
  }
  PoseBlock x = PoseToBlock(T_w_c_guess);
  auto manifold = MakePoseManifold();
  auto loss = MakeLoss(options.loss, options.loss_scale);

  for (int round = 0;; ++round) {
    result.num_inliers =
        static_cast<int>(std::count(result.inliers.begin(), result.inliers.end(), true));
    if (result.num_inliers < options.min_inliers) {
      result.status = PoseOnlyStatus::kTooFewObservations;
      return result;
    }
    ceres::Problem::Options problem_options;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    problem.AddParameterBlock(x.data(), 7, manifold.get());
    for (int i = 0; i < n; ++i) {
      if (!result.inliers[i]) continue;
      problem.AddResidualBlock(CreateReprojectionCost(K, observations[i]), loss.get(), x.data(),
                               p_w[i].data());
      problem.SetParameterBlockConstant(p_w[i].data());
    }
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_QR;
    solver_options.max_num_iterations = options.max_num_iterations;
    solver_options.max_solver_time_in_seconds =
        CeresSolverTimeLimit(options.max_solver_time_in_seconds);
    solver_options.num_threads = options.num_threads;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    result.num_iterations += static_cast<int>(summary.iterations.size());
    if (summary.termination_type == ceres::FAILURE || !summary.IsSolutionUsable()) {
      result.status = PoseOnlyStatus::kSolverFailed;
      return result;
    }
    result.final_cost = summary.final_cost;

    int removed = 0;
    if (options.remove_outliers && round < options.max_outlier_rounds) {
      for (int i = 0; i < n; ++i) {
        if (!result.inliers[i]) continue;
        double depth = 0.0;
        const double e2 = WhitenedSquaredError(K, observations[i], x.data(), p_w[i].data(), &depth);
        const double bound =
            ResidualDof(K, observations[i]) == 3 ? kChi2Quantile95Dof3 : kChi2Quantile95Dof2;
        if (e2 > bound || depth < options.min_depth) {
          result.inliers[i] = false;
          ++removed;
        }
      }
    }
    result.num_outliers_removed += removed;
    if (removed > 0) continue;

    // Covariance from the Jacobian in the manifold tangent (the landmarks are constant).
    ceres::Problem::EvaluateOptions eval_options;
    eval_options.parameter_blocks = {x.data()};
    ceres::CRSMatrix crs;
    problem.Evaluate(eval_options, nullptr, nullptr, nullptr, &crs);
    Matrix6d H = Matrix6d::Zero();
    for (int row = 0; row < crs.num_rows; ++row) {
      Vector6d j = Vector6d::Zero();
      for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k) j[crs.cols[k]] = crs.values[k];
      H.noalias() += j * j.transpose();
    }
    result.T_w_c = BlockToPose(x);
    Eigen::SelfAdjointEigenSolver<Matrix6d> es(H);
    if (!(es.eigenvalues().minCoeff() > 1e-9 * std::max(1.0, es.eigenvalues().maxCoeff()))) {
      result.status = PoseOnlyStatus::kDegenerate;
      return result;
    }
    const Matrix6d cov_manifold = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() *
                                  es.eigenvectors().transpose();
    const Matrix6d A = ManifoldToRightPerturbation(result.T_w_c);
    result.covariance = A * cov_manifold * A.transpose();
    result.status = PoseOnlyStatus::kOk;
    return result;
  }
}

}  // namespace dala
