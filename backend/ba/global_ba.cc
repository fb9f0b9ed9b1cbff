#include "backend/ba/global_ba.h"

#include <ceres/iteration_callback.h>
#include <ceres/problem.h>
#include <ceres/sized_cost_function.h>
#include <ceres/solver.h>
#include <glog/logging.h>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include "backend/ba/pose_block.h"
#include "backend/ba/reprojection_factors.h"

namespace dala {

bool GlobalBaOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(loss_scale > 0.0)) return fail("loss_scale must be > 0");
  if (max_num_iterations < 1) return fail("max_num_iterations must be >= 1");
  if (!(function_tolerance > 0.0)) return fail("function_tolerance must be > 0");
  if (max_outlier_rounds < 0) return fail("max_outlier_rounds must be >= 0");
  if (!(min_depth >= 0.0)) return fail("min_depth must be >= 0");
  if (num_threads < 1) return fail("num_threads must be >= 1");
  if (!(min_disparity_px > 0.0)) return fail("min_disparity_px must be > 0");
  if (!(min_parallax_deg >= 0.0)) return fail("min_parallax_deg must be >= 0");
  if (!(disparity_offset_prior_sigma_px > 0.0)) {
    return fail("disparity_offset_prior_sigma_px must be > 0");
  }
  return true;
}

std::string GlobalBaSummary::BriefReport() const {
  std::ostringstream os;
  os << "global BA: " << num_keyframes << " keyframes, " << num_landmarks << " landmarks ("
     << num_triangulated << " triangulated here), " << num_observations << " observations, "
     << num_outliers_removed << " outliers removed, " << num_solves << " solves / "
     << num_iterations << " iterations, cost " << initial_cost << " -> " << final_cost
     << ", disparity offset " << disparity_offset_px << " px"
     << (stopped  ? " (stopped on request: poses and landmarks unchanged)"
         : usable ? ""
                  : " (NOT usable)");
  return os.str();
}

namespace {

// Ends a solve (SOLVER_ABORT: the solution is then not usable) once the caller asks to stop.
class StopCallback : public ceres::IterationCallback {
 public:
  explicit StopCallback(std::function<bool()> stop) : stop_(std::move(stop)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return stop_() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<bool()> stop_;
};

// r = (|t_b - t_a| - d) / sigma on two pose blocks x = [q; t] (backend/ba/pose_block.h):
// dr/dt_b = u^T / sigma, dr/dt_a = -u^T / sigma with u the unit vector from a to b; the
// quaternion columns are zero (the manifold's Plus Jacobian maps them to the tangent).
class DistanceCost : public ceres::SizedCostFunction<1, 7, 7> {
 public:
  explicit DistanceCost(double distance) : d_(distance), inv_sigma_(1.0 / (1e-6 * distance)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> t_a(parameters[0] + 4), t_b(parameters[1] + 4);
    const Eigen::Vector3d delta = t_b - t_a;
    const double norm = delta.norm();
    residuals[0] = (norm - d_) * inv_sigma_;
    if (jacobians == nullptr) return true;
    const Eigen::Vector3d u = norm > 0.0 ? Eigen::Vector3d(delta / norm) : Eigen::Vector3d::Zero();
    for (int k = 0; k < 2; ++k) {
      if (jacobians[k] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, 1, 7>> J(jacobians[k]);
      J.setZero();
      J.tail<3>() = (k == 0 ? -inv_sigma_ : inv_sigma_) * u.transpose();
    }
    return true;
  }

 private:
  double d_;
  double inv_sigma_;
};

// Positions of the observed landmarks that have none (see Options::triangulate_unmapped).
std::map<LandmarkId, Eigen::Vector3d> TriangulateUnmapped(const StereoIntrinsics& K,
                                                          const GlobalBaOptions& options,
                                                          const GlobalBaProblem& problem) {
  struct Views {
    std::vector<Pose> T_w_c;
    std::vector<Eigen::Vector2d> uv;
    std::optional<Eigen::Vector3d> p_w_stereo;  // From the first stereo observation.
  };
  std::map<LandmarkId, Views> views;
  for (const auto& [kf, obs] : problem.observations) {
    const auto pose = problem.keyframes.find(kf);
    if (pose == problem.keyframes.end() || problem.landmarks.count(obs.landmark)) continue;
    Views& v = views[obs.landmark];
    v.T_w_c.push_back(pose->second);
    v.uv.push_back(obs.uv);
    if (!v.p_w_stereo) {
      if (const auto p_c = TriangulateStereo(K, obs, options.min_disparity_px)) {
        v.p_w_stereo = pose->second * *p_c;
      }
    }
  }
  std::map<LandmarkId, Eigen::Vector3d> out;
  for (const auto& [id, v] : views) {
    if (v.T_w_c.size() < 2) continue;
    if (v.p_w_stereo) {
      out[id] = *v.p_w_stereo;
    } else if (const auto p_w = TriangulateViews(K, v.T_w_c, v.uv, options.min_parallax_deg,
                                                 options.min_depth)) {
      out[id] = *p_w;
    }
  }
  return out;
}

}  // namespace

GlobalBaSummary SolveGlobalBa(const StereoIntrinsics& K_in, const GlobalBaOptions& options,
                              GlobalBaProblem* problem,
                              const std::function<bool()>& stop_requested) {
  // K's disparity offset follows the estimate (Options::estimate_disparity_offset) from one
  // solve to the next, so that the outlier test judges each residual under it.
  StereoIntrinsics K = K_in;
  const bool estimate_offset = options.estimate_disparity_offset && K.is_stereo();
  double offset = K.disparity_offset_px;
  std::string why;
  CHECK(options.IsValid(&why)) << "invalid GlobalBaOptions: " << why;
  const auto t0 = std::chrono::steady_clock::now();
  GlobalBaSummary summary;
  summary.usable = true;

  // Solved on copies: a solve that fails leaves the problem's values as they were.
  std::map<KeyframeId, PoseBlock> x;
  for (const auto& [id, T_w_c] : problem->keyframes) x[id] = PoseToBlock(T_w_c);
  std::map<LandmarkId, Eigen::Vector3d> p = problem->landmarks;
  std::set<LandmarkId> triangulated;
  if (options.triangulate_unmapped) {
    for (const auto& [id, p_w] : TriangulateUnmapped(K, options, *problem)) {
      p[id] = p_w;
      triangulated.insert(id);
    }
  }
  auto& observations = problem->observations;
  const auto usable_observation = [&](const std::pair<KeyframeId, BaObservation>& o) {
    return x.count(o.first) && p.count(o.second.landmark);
  };

  std::set<KeyframeId> optimised;            // In some solve.
  std::set<LandmarkId> last_used_landmarks;  // In the last solve.
  auto manifold = MakePoseManifold();
  auto loss = MakeLoss(options.loss, options.loss_scale);
  const auto stop = [&] { return stop_requested && stop_requested(); };
  StopCallback stop_callback(stop);
  for (int round = 0;; ++round) {
    if (stop()) {
      summary.stopped = true;
      summary.usable = false;
      break;
    }
    // A landmark enters when two keyframes observe it (one view constrains nothing).
    std::map<LandmarkId, int> views;
    for (const auto& o : observations) {
      if (usable_observation(o)) ++views[o.second.landmark];
    }
    ceres::Problem::Options problem_options;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem ceres_problem(problem_options);
    std::set<KeyframeId> used_keyframes;
    std::set<LandmarkId> used_landmarks;
    for (const auto& [kf, obs] : observations) {
      if (!x.count(kf) || views[obs.landmark] < 2) continue;
      double* x_kf = x.at(kf).data();
      if (used_keyframes.insert(kf).second) {
        ceres_problem.AddParameterBlock(x_kf, 7, manifold.get());
        if (problem->held.count(kf)) ceres_problem.SetParameterBlockConstant(x_kf);
      }
      used_landmarks.insert(obs.landmark);
      if (estimate_offset && obs.u_right) {
        ceres_problem.AddResidualBlock(CreateStereoOffsetCost(K, obs), loss.get(), x_kf,
                                       p.at(obs.landmark).data(), &offset);
      } else {
        ceres_problem.AddResidualBlock(CreateReprojectionCost(K, obs), loss.get(), x_kf,
                                       p.at(obs.landmark).data());
      }
    }
    last_used_landmarks = used_landmarks;
    if (round == 0) {
      summary.num_keyframes = static_cast<int>(used_keyframes.size());
      summary.num_landmarks = static_cast<int>(used_landmarks.size());
      for (LandmarkId id : triangulated) summary.num_triangulated += used_landmarks.count(id);
      summary.num_observations = ceres_problem.NumResidualBlocks();
    }
    if (ceres_problem.NumResidualBlocks() == 0) break;
    if (ceres_problem.HasParameterBlock(&offset)) {
      ceres_problem.AddResidualBlock(CreateOffsetPriorCost(options.disparity_offset_prior_sigma_px),
                                     nullptr, &offset);
    }
    for (const GlobalBaProblem::FixedDistance& f : problem->fixed_distances) {
      if (used_keyframes.count(f.a) && used_keyframes.count(f.b) && f.distance > 0.0) {
        ceres_problem.AddResidualBlock(new DistanceCost(f.distance), nullptr, x.at(f.a).data(),
                                       x.at(f.b).data());
      }
    }
    optimised.insert(used_keyframes.begin(), used_keyframes.end());

    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
    solver_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
    solver_options.max_num_iterations = options.max_num_iterations;
    solver_options.function_tolerance = options.function_tolerance;
    solver_options.num_threads = options.num_threads;
    solver_options.logging_type = ceres::SILENT;
    solver_options.callbacks.push_back(&stop_callback);
    ceres::Solver::Summary ceres_summary;
    ceres::Solve(solver_options, &ceres_problem, &ceres_summary);
    VLOG(2) << ceres_summary.BriefReport();
    ++summary.num_solves;
    summary.num_iterations += static_cast<int>(ceres_summary.iterations.size());
    if (round == 0) summary.initial_cost = ceres_summary.initial_cost;
    summary.final_cost = ceres_summary.final_cost;
    summary.usable = ceres_summary.IsSolutionUsable();
    if (stop()) {
      summary.stopped = true;
      summary.usable = false;
    }
    if (!summary.usable) break;
    K.disparity_offset_px = offset;

    // The chi-square test on every residual at the solution.
    int removed = 0;
    std::vector<std::pair<KeyframeId, BaObservation>> kept;
    kept.reserve(observations.size());
    for (auto& o : observations) {
      if (usable_observation(o) && views[o.second.landmark] >= 2) {
        double depth = 0.0;
        const double e2 = WhitenedSquaredError(K, o.second, x.at(o.first).data(),
                                               p.at(o.second.landmark).data(), &depth);
        const double bound =
            ResidualDof(K, o.second) == 3 ? kChi2Quantile95Dof3 : kChi2Quantile95Dof2;
        if (e2 > bound || depth < options.min_depth) {
          ++removed;
          continue;
        }
      }
      kept.push_back(std::move(o));
    }
    observations = std::move(kept);
    summary.num_outliers_removed += removed;
    if (removed == 0 || round >= options.max_outlier_rounds) break;
  }

  // Only what a solve could move is written back (a held pose or an unused one stays exact).
  if (summary.usable && summary.num_solves > 0) {
    for (auto& [id, T_w_c] : problem->keyframes) {
      if (optimised.count(id) && !problem->held.count(id)) T_w_c = BlockToPose(x.at(id));
    }
    // The triangulated landmarks that left the last solve are not kept.
    for (LandmarkId id : triangulated) {
      if (!last_used_landmarks.count(id)) p.erase(id);
    }
    problem->landmarks = std::move(p);
  }
  summary.disparity_offset_px = summary.usable ? K.disparity_offset_px : K_in.disparity_offset_px;
  summary.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace dala
