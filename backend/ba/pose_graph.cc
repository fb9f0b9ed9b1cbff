#include "backend/ba/pose_graph.h"

#include <ceres/problem.h>
#include <ceres/solver.h>
#include <glog/logging.h>

#include <chrono>

#include "backend/ba/pose_block.h"
#include "backend/ba/pose_graph_problem.h"
#include "backend/ba/relative_pose_cost.h"
#include "backend/ba/solver_time.h"

namespace dala {

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
  SolvePoseGraph(
      &blocks, manifold.get(), edges, options,
      [](const PoseGraphEdge& e, const Matrix6d& sqrt_info) {
        return CreateRelativePoseCost(e.T_from_to, sqrt_info);
      },
      &s);
  if (!s.usable) return T_w_kf;
  std::map<KeyframeId, Pose> out;
  for (const auto& [id, x] : blocks) out[id] = BlockToPose(x);
  return out;
}

}  // namespace dala
