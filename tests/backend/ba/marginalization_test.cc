#include "backend/ba/marginalization.h"

#include <ceres/crs_matrix.h>
#include <ceres/numeric_diff_cost_function.h>
#include <ceres/problem.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "backend/ba/reprojection_factors.h"
#include "tests/backend/ba/ba_synthetic_scene.h"
#include "tests/test_util.h"

namespace dala {
namespace {

TEST(PoseBlockMinusTest, InvertsTheManifoldPlus) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  auto manifold = MakePoseManifold();
  for (int trial = 0; trial < 20; ++trial) {
    const PoseBlock x = PoseToBlock(testing::RandomPose(rng));
    double d[6], y[7], m[6];
    for (double& v : d) v = 0.3 * n(rng);
    ASSERT_TRUE(manifold->Plus(x.data(), d, y));
    const Vector6d ours = PoseBlockMinus(y, x.data());
    ASSERT_TRUE(manifold->Minus(y, x.data(), m));
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(ours[i], d[i], 1e-12);
      EXPECT_NEAR(ours[i], m[i], 1e-12);
    }
  }
}

TEST(PoseBlockTest, ManifoldToRightPerturbationMatchesFirstOrder) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  auto manifold = MakePoseManifold();
  const Pose T = testing::RandomPose(rng);
  const PoseBlock x = PoseToBlock(T);
  Vector6d d;
  for (int i = 0; i < 6; ++i) d[i] = 1e-6 * n(rng);
  PoseBlock y;
  ASSERT_TRUE(manifold->Plus(x.data(), d.data(), y.data()));
  const Vector6d xi = LogSE3(T.inverse() * BlockToPose(y));
  const Vector6d predicted = ManifoldToRightPerturbation(T) * d;
  EXPECT_LT((xi - predicted).norm(), 1e-10 + 1e-4 * xi.norm()) << xi.transpose() << "\n"
                                                               << predicted.transpose();
}

// The prior equals the Schur complement of the dense Gauss-Newton system built independently
// from ceres::Problem::Evaluate: S^T S = H_kk - H_km H_mm^-1 H_mk, S^T r0 = b_k - H_km H_mm^-1 b_m.
TEST(MarginalizeTest, MatchesDenseSchurComplement) {
  testing::BaSceneOptions scene_options;
  scene_options.num_keyframes = 4;
  scene_options.num_points = 40;
  const testing::BaScene scene = testing::MakeBaScene(scene_options);
  std::mt19937 rng(5);
  std::vector<PoseBlock> x;
  for (const Pose& T : scene.T_w_c_gt)
    x.push_back(PoseToBlock(testing::PerturbPose(T, rng, 0.01, 0.05)));
  std::vector<Eigen::Vector3d> p = scene.p_w_gt;
  for (auto& v : p) v += 0.05 * Eigen::Vector3d::Random();

  // Marginalise keyframe 1 and the landmarks it sees; keyframe 0 constant; keep 2 and 3.
  std::set<int64_t> leaving;
  for (const auto& o : scene.keyframes[1].observations) leaving.insert(o.landmark.value);
  auto loss = std::make_unique<ceres::HuberLoss>(2.0);
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  MarginalizationInput input;
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  auto manifold = MakePoseManifold();
  for (auto& xi : x) problem.AddParameterBlock(xi.data(), 7, manifold.get());
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    for (const auto& o : scene.keyframes[k].observations) {
      if (!leaving.count(o.landmark.value)) continue;
      costs.emplace_back(CreateReprojectionCost(scene.K, o));
      double* lm = p[o.landmark.value].data();
      input.factors.push_back({costs.back().get(), loss.get(), {x[k].data(), lm}});
      problem.AddResidualBlock(costs.back().get(), loss.get(), x[k].data(), lm);
    }
  }
  problem.SetParameterBlockConstant(x[0].data());
  input.marginalized_poses = {x[1].data()};
  std::vector<double*> ordering = {x[1].data()};
  for (int64_t id : leaving) {
    input.marginalized_landmarks.push_back(p[id].data());
    ordering.push_back(p[id].data());
  }
  input.kept_poses = {{KeyframeId(2), x[2].data()}, {KeyframeId(3), x[3].data()}};
  ordering.push_back(x[2].data());
  ordering.push_back(x[3].data());
  const MarginalizationPrior prior = Marginalize(input);
  ASSERT_EQ(prior.keyframes.size(), 2u);
  EXPECT_EQ(prior.rank(), 12);

  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = ordering;
  ceres::CRSMatrix crs;
  std::vector<double> residuals;
  ASSERT_TRUE(problem.Evaluate(eo, nullptr, &residuals, nullptr, &crs));
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) J(r, crs.cols[k]) = crs.values[k];
  }
  const Eigen::VectorXd res = Eigen::Map<Eigen::VectorXd>(residuals.data(), residuals.size());
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd b = J.transpose() * res;
  const int nm = crs.num_cols - 12;
  const Eigen::MatrixXd Hmm_inv = H.topLeftCorner(nm, nm).inverse();
  const Eigen::MatrixXd Hkm = H.bottomLeftCorner(12, nm);
  const Eigen::MatrixXd H_schur = H.bottomRightCorner(12, 12) - Hkm * Hmm_inv * Hkm.transpose();
  const Eigen::VectorXd b_schur = b.tail(12) - Hkm * Hmm_inv * b.head(nm);
  const Eigen::MatrixXd H_prior = prior.sqrt_information.transpose() * prior.sqrt_information;
  const Eigen::VectorXd b_prior = prior.sqrt_information.transpose() * prior.r0;
  // Ceres's robust-loss correction differs from plain IRLS only for residuals in the
  // non-quadratic region; with these small perturbations all are quadratic.
  EXPECT_LT((H_prior - H_schur).norm(), 1e-6 * H_schur.norm());
  EXPECT_LT((b_prior - b_schur).norm(), 1e-6 * (1.0 + b_schur.norm()));

  // The prior cost function evaluates to r0 at x_lin and its Jacobian (times PlusJacobian) is S.
  std::unique_ptr<ceres::CostFunction> prior_cost(CreatePriorCost(prior));
  double* blocks[2] = {x[2].data(), x[3].data()};
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J0(prior.rank(), 7),
      J1(prior.rank(), 7);
  double* jacs[2] = {J0.data(), J1.data()};
  Eigen::VectorXd r(prior.rank());
  ASSERT_TRUE(prior_cost->Evaluate(blocks, r.data(), jacs));
  EXPECT_LT((r - prior.r0).norm(), 1e-12);
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> P0, P1;
  manifold->PlusJacobian(x[2].data(), P0.data());
  manifold->PlusJacobian(x[3].data(), P1.data());
  EXPECT_LT((J0 * P0 - prior.sqrt_information.leftCols(6)).norm(), 1e-9);
  EXPECT_LT((J1 * P1 - prior.sqrt_information.rightCols(6)).norm(), 1e-9);
}

}  // namespace
}  // namespace dala
