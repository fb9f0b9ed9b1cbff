#include "backend/ba/pose_graph.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <glog/logging.h>

#include <chrono>

#include "backend/ba/pose_block.h"
#include "backend/ba/pose_graph_problem.h"
#include "backend/ba/solver_time.h"

namespace dala {
namespace {

struct RelativePoseError {
  RelativePoseError(const Pose& T_a_b_meas, const Matrix6d& sqrt_info)
      : q_b_a_meas_(Eigen::Quaterniond(T_a_b_meas.rotation()).conjugate()),
        t_a_b_meas_(T_a_b_meas.translation()),
        sqrt_info_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* x_a, const T* x_b, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_a(x_a);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_w_a(x_a + 4);
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_b(x_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_w_b(x_b + 4);
    // Estimated T_a_b.
    const Eigen::Quaternion<T> q_a_w = q_w_a.conjugate();
    const Eigen::Quaternion<T> q_a_b = q_a_w * q_w_b;
    const Eigen::Matrix<T, 3, 1> t_a_b = q_a_w * (t_w_b - t_w_a);
    // T_err = T_a_b_meas^-1 * T_a_b = [R_meas^T R_a_b, R_meas^T (t_a_b - t_meas)].
    const Eigen::Quaternion<T> q_meas_inv = q_b_a_meas_.template cast<T>();
    Eigen::Quaternion<T> q_err = q_meas_inv * q_a_b;
    if (q_err.w() < T(0.0)) q_err.coeffs() = -q_err.coeffs();
    const Eigen::Matrix<T, 3, 1> t_err = q_meas_inv * (t_a_b - t_a_b_meas_.template cast<T>());
    Eigen::Matrix<T, 6, 1> e;
    e << T(2.0) * q_err.vec(), t_err;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> res(r);
    res = sqrt_info_.template cast<T>() * e;
    return true;
  }

  static ceres::CostFunction* Create(const Pose& T_a_b_meas, const Matrix6d& sqrt_info) {
    return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 7, 7>(
        new RelativePoseError(T_a_b_meas, sqrt_info));
  }

 private:
  Eigen::Quaterniond q_b_a_meas_;
  Eigen::Vector3d t_a_b_meas_;
  Matrix6d sqrt_info_;
};

}  // namespace

bool PoseGraphOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (max_num_iterations < 1) return fail("max_num_iterations must be >= 1");
  if (!(max_solver_time_in_seconds >= 0.0)) {
    return fail("max_solver_time_in_seconds must be >= 0 (0: no time limit)");
  }
  if (!(loss_scale > 0.0)) return fail("loss_scale must be > 0");
  if (num_threads < 1) return fail("num_threads must be >= 1");
  return true;
}

void SolvePoseGraphProblem(const PoseGraphOptions& options, ceres::Problem* problem,
                           PoseGraphSummary* s) {
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  solver_options.max_num_iterations = options.max_num_iterations;
  solver_options.max_solver_time_in_seconds =
      CeresSolverTimeLimit(options.max_solver_time_in_seconds);
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, problem, &ceres_summary);
  s->usable = ceres_summary.IsSolutionUsable();
  s->num_iterations = static_cast<int>(ceres_summary.iterations.size());
  s->initial_cost = ceres_summary.initial_cost;
  s->final_cost = ceres_summary.final_cost;
  s->time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::map<KeyframeId, Pose> OptimizePoseGraph(const std::map<KeyframeId, Pose>& T_w_kf,
                                             const std::vector<PoseGraphEdge>& edges,
                                             const PoseGraphOptions& options,
                                             PoseGraphSummary* summary) {
  std::string why;
  CHECK(options.IsValid(&why)) << "invalid PoseGraphOptions: " << why;
  PoseGraphSummary local;
  PoseGraphSummary& s = summary ? *summary : local;
  s = PoseGraphSummary();
  if (T_w_kf.empty()) return T_w_kf;

  std::map<KeyframeId, PoseBlock> blocks;
  for (const auto& [id, T] : T_w_kf) blocks[id] = PoseToBlock(T);
  auto manifold = MakePoseManifold();
  SolvePoseGraph(&blocks, manifold.get(), edges, options,
                 [](const PoseGraphEdge& e, const Matrix6d& sqrt_info) {
                   return RelativePoseError::Create(e.T_from_to, sqrt_info);
                 },
                 &s);
  if (!s.usable) return T_w_kf;
  std::map<KeyframeId, Pose> out;
  for (const auto& [id, x] : blocks) out[id] = BlockToPose(x);
  return out;
}

}  // namespace dala
