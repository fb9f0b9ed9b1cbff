#include "backend/ba/sliding_window_ba.h"

#include <ceres/problem.h>
#include <ceres/solver.h>
#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <sstream>

#include "backend/ba/relative_pose_cost.h"
#include "backend/ba/reprojection_factors.h"
#include "backend/ba/solver_time.h"

namespace dala {
namespace {

// The window's problems borrow the manifold and loss objects, which outlive them.
ceres::Problem::Options BorrowingProblemOptions() {
  ceres::Problem::Options options;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return options;
}

}  // namespace

bool SlidingWindowBa::Options::IsValid(std::string* why) const {
  auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (window_size < 2) return fail("window_size must be >= 2");
  if (num_fixed_keyframes < -1) return fail("num_fixed_keyframes must be >= 0 (or -1 = auto)");
  if (num_held_keyframes < -1) return fail("num_held_keyframes must be >= 0 (or -1 = auto)");
  if (!(loss_scale > 0.0)) return fail("loss_scale must be > 0");
  if (max_num_iterations < 1) return fail("max_num_iterations must be >= 1");
  if (!(max_solver_time_in_seconds >= 0.0)) {
    return fail("max_solver_time_in_seconds must be >= 0 (0: no time limit)");
  }
  if (!(function_tolerance > 0.0)) return fail("function_tolerance must be > 0");
  if (num_threads < 1) return fail("num_threads must be >= 1");
  if (max_outlier_rounds < 0) return fail("max_outlier_rounds must be >= 0");
  if (!(disparity_offset_prior_sigma_px > 0.0))
    return fail("disparity_offset_prior_sigma_px must be > 0");
  if (!std::isfinite(disparity_offset_px) || std::abs(disparity_offset_px) > 10.0) {
    return fail("disparity_offset_px must be within +-10 px (a rig's rectification error)");
  }
  if (!offset_calibration.IsValid(why)) return false;
  if (min_observations < 1) return fail("min_observations must be >= 1");
  if (!(min_disparity_px > 0.0)) return fail("min_disparity_px must be > 0");
  if (!(min_triangulation_parallax_deg > 0.0)) {
    return fail("min_triangulation_parallax_deg must be > 0");
  }
  if (!(min_depth > 0.0)) return fail("min_depth must be > 0");
  if (!(fuse_radius_px >= 0.0)) return fail("fuse_radius_px must be >= 0 (0: no fusion)");
  if (!(prior_eigenvalue_floor > 0.0 && prior_eigenvalue_floor < 1.0)) {
    return fail("prior_eigenvalue_floor must be in (0, 1)");
  }
  return true;
}

std::string SlidingWindowBa::Summary::BriefReport() const {
  std::ostringstream os;
  os << "BA: " << num_keyframes << " keyframes (+" << num_held_keyframes << " held), "
     << num_landmarks << " landmarks, "
     << num_residual_blocks << " residual blocks, " << num_solves << " solves, " << num_iterations
     << " iterations, cost " << initial_cost << " -> " << final_cost << ", " << num_outliers_removed
     << " outliers removed, " << num_landmarks_culled << " landmarks culled, " << time_s * 1e3
     << " ms" << (usable ? "" : " (NOT usable)");
  return os.str();
}

SlidingWindowBa::SlidingWindowBa(const StereoIntrinsics& K, const Options& options)
    : K_(K), options_(options), offset_calibration_(options.offset_calibration) {
  std::string why;
  CHECK(K_.IsValid(&why)) << "invalid StereoIntrinsics: " << why;
  CHECK(options_.IsValid(&why)) << "invalid SlidingWindowBa::Options: " << why;
  num_fixed_ =
      options_.num_fixed_keyframes >= 0 ? options_.num_fixed_keyframes : (K_.is_stereo() ? 1 : 2);
  num_held_ =
      options_.num_held_keyframes >= 0 ? options_.num_held_keyframes : (K_.is_stereo() ? 0 : 2);
}

void SlidingWindowBa::SetLandmarkPosition(LandmarkId id, const Eigen::Vector3d& p_w) {
  landmarks_[id] = p_w;
}

bool SlidingWindowBa::IsHeldConstant(size_t i) const {
  // Gauge of the window optimisation: the oldest num_fixed_ window keyframes, whatever the
  // marginalisation mode. The prior must NOT be left to hold the gauge. Its information on the
  // absolute pose of the window (the chain back to the first keyframe) decays as the path grows
  // (rover loop: smallest eigenvalue 646 at the start, 3.5 after 240 keyframes, against 2e8 for
  // the largest), so the 6 gauge directions soon fall below the eigenvalue floor or are held by
  // a stiffness of ~1: a free or nearly free rigid motion of the whole window. The reprojection
  // factors are exactly invariant to it and the prior, linearised at x_lin in the SO(3) x R^3
  // tangent, is only approximately so; the small gradient this mismatch leaves along the soft
  // direction then moves the window by metres in one solve (measured: 3.5 deg, 2.9 m at frame
  // 818 with a prior cost unchanged at ~7; the trajectory jumps and never comes back).
  // Holding the oldest keyframe removes the gauge from the solve; the prior still carries its
  // information: the oldest keyframe's pose enters every marginalisation as a VARIABLE (see
  // MarginalizeOldest), so its uncertainty is marginalised, not conditioned on.
  return window_[i].fixed || static_cast<int>(i) < num_fixed_;
}

void SlidingWindowBa::AddKeyframe(const BaKeyframe& kf) {
  CHECK(window_.empty() || window_.back().id < kf.id)
      << "keyframe ids must increase: " << kf.id << " after " << window_.back().id;
  if (static_cast<int>(window_.size()) >= options_.window_size) MarginalizeOldest();
  KeyframeState state;
  state.id = kf.id;
  state.t_ns = kf.t_ns;
  state.x = PoseToBlock(kf.T_w_c);
  state.fixed = num_added_ < num_fixed_;
  state.observations = kf.observations;
  ++num_added_;
  window_.push_back(std::move(state));
  InitializeStereoLandmarks(window_.back());
}

void SlidingWindowBa::AddRelativePosePrior(KeyframeId a, KeyframeId b, const Pose& T_a_b,
                                           const Matrix6d& information) {
  CHECK(BlockOf(a) != nullptr && BlockOf(b) != nullptr)
      << "relative-pose prior between keyframes " << a << " and " << b
      << ", which are not both in the window or held";
  const Eigen::LLT<Matrix6d> llt(0.5 * (information + information.transpose()));
  CHECK(llt.info() == Eigen::Success) << "relative-pose prior: information not positive definite";
  relative_priors_.push_back({a, b, T_a_b, llt.matrixU()});
}

double* SlidingWindowBa::BlockOf(KeyframeId id) {
  for (auto* keyframes : {&window_, &held_}) {
    for (KeyframeState& kf : *keyframes) {
      if (kf.id == id) return kf.x.data();
    }
  }
  return nullptr;
}

void SlidingWindowBa::ForgetLandmarks(const std::vector<LandmarkId>& ids) {
  if (ids.empty()) return;
  std::set<LandmarkId> observed;
  for (auto* keyframes : {&held_, &window_}) {
    for (const KeyframeState& kf : *keyframes) {
      for (const BaObservation& obs : kf.observations) observed.insert(obs.landmark);
    }
  }
  for (const LandmarkId id : ids) {
    if (!observed.count(id)) landmarks_.erase(id);
  }
}

void SlidingWindowBa::AddObservation(KeyframeId id, const BaObservation& obs) {
  for (KeyframeState& kf : window_) {
    if (kf.id != id) continue;
    kf.observations.push_back(obs);
    return;
  }
  LOG(FATAL) << "AddObservation: keyframe " << id << " is not in the window";
}

void SlidingWindowBa::ApplyCorrection(const std::map<KeyframeId, Pose>& T_w_kf) {
  for (auto* keyframes : {&held_, &window_}) {
    for (KeyframeState& kf : *keyframes) {
      const auto it = T_w_kf.find(kf.id);
      if (it != T_w_kf.end()) kf.x = PoseToBlock(it->second);
    }
  }
  DropPrior();
  // A similarity correction (one camera) rescales the relative translations they hold.
  relative_priors_.clear();
}

void SlidingWindowBa::DropPrior() {
  if (prior_.empty()) return;
  prior_ = MarginalizationPrior();
  if (!window_.empty()) window_.front().fixed = true;
}

void SlidingWindowBa::InitializeStereoLandmarks(const KeyframeState& kf) {
  const Pose T_w_c = BlockToPose(kf.x);
  for (const BaObservation& obs : kf.observations) {
    if (landmarks_.count(obs.landmark)) continue;
    if (auto p_c = TriangulateStereo(K_, obs, options_.min_disparity_px)) {
      landmarks_[obs.landmark] = T_w_c * *p_c;
    }
  }
}

std::map<LandmarkId, int> SlidingWindowBa::CountObservations() const {
  std::map<LandmarkId, int> counts;
  for (const KeyframeState& kf : window_) {
    for (const BaObservation& obs : kf.observations) ++counts[obs.landmark];
  }
  return counts;
}

bool SlidingWindowBa::IsActive(LandmarkId id, const std::map<LandmarkId, int>& counts) const {
  const auto it = counts.find(id);
  return it != counts.end() && it->second >= options_.min_observations && landmarks_.count(id);
}

bool SlidingWindowBa::TriangulateMono(LandmarkId id, Eigen::Vector3d* p_w) const {
  std::vector<Pose> poses;
  std::vector<Eigen::Vector2d> uv;
  for (const KeyframeState& kf : window_) {
    for (const BaObservation& obs : kf.observations) {
      if (obs.landmark != id) continue;
      poses.push_back(BlockToPose(kf.x));
      uv.push_back(obs.uv);
    }
  }
  const std::optional<Eigen::Vector3d> p = TriangulateViews(
      K_, poses, uv, options_.min_triangulation_parallax_deg, options_.min_depth);
  if (!p) return false;
  *p_w = *p;
  return true;
}

void SlidingWindowBa::InitializeMonoLandmarks() {
  const auto counts = CountObservations();
  for (const auto& [id, n] : counts) {
    if (n < 2 || landmarks_.count(id)) continue;
    Eigen::Vector3d p_w;
    if (TriangulateMono(id, &p_w)) landmarks_[id] = p_w;
  }
}

void SlidingWindowBa::MarginalizeOldest() {
  CHECK(!window_.empty());
  KeyframeState& m = window_.front();
  marginalized_.push_back({m.id, m.t_ns, BlockToPose(m.x)});
  if (!options_.use_marginalization) {
    Hold(std::move(m), {});
    window_.pop_front();
    return;
  }
  const auto counts = CountObservations();
  std::set<LandmarkId> tracked;  // seen by the newest keyframe.
  for (const BaObservation& obs : window_.back().observations) tracked.insert(obs.landmark);
  // A landmark of m stays in the state (m's observation of it is dropped with m) when it keeps
  // enough observations and the exit mode keeps it; else it leaves, marginalised with all its
  // window observations.
  const auto stays = [&](LandmarkId id) {
    const bool enough = counts.at(id) - 1 >= options_.min_observations;
    switch (options_.landmark_exit) {
      case LandmarkExit::kDropTrackedObservations:
        return enough && tracked.count(id) > 0;
      case LandmarkExit::kDropSharedObservations:
        return enough;
      case LandmarkExit::kMarginalizeAll:
      case LandmarkExit::kMarginalizeAllKeepTracks:
        return false;
    }
    return false;
  };
  std::set<LandmarkId> leaving;
  for (const BaObservation& obs : m.observations) {
    if (IsActive(obs.landmark, counts) && !stays(obs.landmark)) leaving.insert(obs.landmark);
  }
  std::map<KeyframeId, double*> block_of;
  for (KeyframeState& kf : window_) block_of[kf.id] = kf.x.data();

  auto loss = MakeLoss(options_.loss, options_.loss_scale);
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  MarginalizationInput input;
  input.eigenvalue_floor = options_.prior_eigenvalue_floor;
  for (KeyframeState& kf : window_) {
    for (const BaObservation& obs : kf.observations) {
      if (!leaving.count(obs.landmark)) continue;
      costs.emplace_back(CreateReprojectionCost(K_, obs));
      input.factors.push_back(
          {costs.back().get(), loss.get(), {kf.x.data(), landmarks_.at(obs.landmark).data()}});
    }
  }
  if (!prior_.empty()) {
    costs.emplace_back(CreatePriorCost(prior_));
    FactorRef f{costs.back().get(), nullptr, {}};
    for (KeyframeId id : prior_.keyframes) f.blocks.push_back(block_of.at(id));
    input.factors.push_back(f);
  }
  // Only the first keyframes ever added (`fixed`) are constants of the prior. A keyframe held
  // constant in the window solves for the gauge (IsHeldConstant) is a variable here: it sits at
  // its x_lin (it has not moved since the prior that holds it was built), and the prior is the
  // Gaussian of all window poses relative to the fixed first keyframes, so the leaving pose is
  // marginalised (Schur complement), not conditioned on. The window solve then conditions the
  // prior on the next oldest keyframe, which it holds.
  if (!m.fixed) input.marginalized_poses.push_back(m.x.data());
  for (LandmarkId id : leaving) input.marginalized_landmarks.push_back(landmarks_.at(id).data());
  for (size_t i = 1; i < window_.size(); ++i) {
    if (!window_[i].fixed) input.kept_poses.push_back({window_[i].id, window_[i].x.data()});
  }
  prior_ = options_.keep_prior ? Marginalize(input) : MarginalizationPrior();

  // The marginalised landmarks leave the state: their observations are consumed. Their last
  // estimate stays in landmarks_ as the initial value if they are observed again.
  Hold(std::move(m), leaving);
  window_.pop_front();
  // kMarginalizeAllKeepTracks: the tracked landmarks also keep their window observations.
  const bool keep_tracked = options_.landmark_exit == LandmarkExit::kMarginalizeAllKeepTracks;
  for (KeyframeState& kf : window_) {
    auto& obs = kf.observations;
    obs.erase(std::remove_if(obs.begin(), obs.end(),
                             [&](const BaObservation& o) {
                               return leaving.count(o.landmark) > 0 &&
                                      !(keep_tracked && tracked.count(o.landmark) > 0);
                             }),
              obs.end());
  }
}

void SlidingWindowBa::Hold(KeyframeState leaving, const std::set<LandmarkId>& consumed) {
  if (num_held_ == 0) return;
  auto& obs = leaving.observations;
  obs.erase(std::remove_if(obs.begin(), obs.end(),
                           [&](const BaObservation& o) { return consumed.count(o.landmark) > 0; }),
            obs.end());
  obs.shrink_to_fit();
  leaving.fixed = true;
  held_.push_back(std::move(leaving));
  while (static_cast<int>(held_.size()) > num_held_) held_.pop_front();
}

std::set<LandmarkId> SlidingWindowBa::BuildProblem(const std::map<LandmarkId, int>& counts,
                                                   ceres::Manifold* manifold,
                                                   ceres::LossFunction* loss, double* offset,
                                                   bool with_prior, ceres::Problem* problem,
                                                   int* num_held_used) {
  for (size_t i = 0; i < window_.size(); ++i) {
    problem->AddParameterBlock(window_[i].x.data(), 7, manifold);
    if (IsHeldConstant(i)) problem->SetParameterBlockConstant(window_[i].x.data());
  }
  std::set<LandmarkId> active;
  const auto add_residual = [&](KeyframeState& kf, const BaObservation& obs) {
    double* p_w = landmarks_.at(obs.landmark).data();
    if (offset != nullptr && ResidualDof(K_, obs) == 3) {
      problem->AddResidualBlock(CreateStereoOffsetCost(K_, obs), loss, kf.x.data(), p_w, offset);
    } else {
      problem->AddResidualBlock(CreateReprojectionCost(K_, obs), loss, kf.x.data(), p_w);
    }
  };
  for (KeyframeState& kf : window_) {
    for (const BaObservation& obs : kf.observations) {
      if (!IsActive(obs.landmark, counts)) continue;
      active.insert(obs.landmark);
      add_residual(kf, obs);
    }
  }
  // The held keyframes: constants, with their observations of the active landmarks.
  *num_held_used = 0;
  for (KeyframeState& kf : held_) {
    bool used = false;
    for (const BaObservation& obs : kf.observations) {
      if (!IsActive(obs.landmark, counts)) continue;
      if (!used) {
        problem->AddParameterBlock(kf.x.data(), 7, manifold);
        problem->SetParameterBlockConstant(kf.x.data());
        used = true;
      }
      add_residual(kf, obs);
    }
    *num_held_used += used ? 1 : 0;
  }
  // The relative-pose priors whose keyframes are both here, one of them free.
  for (const RelativePosePrior& r : relative_priors_) {
    double* x_a = BlockOf(r.a);
    double* x_b = BlockOf(r.b);
    if (x_a == nullptr || x_b == nullptr) continue;
    for (double* x : {x_a, x_b}) {
      if (!problem->HasParameterBlock(x)) {
        problem->AddParameterBlock(x, 7, manifold);
        problem->SetParameterBlockConstant(x);
      }
    }
    if (problem->IsParameterBlockConstant(x_a) && problem->IsParameterBlockConstant(x_b)) continue;
    problem->AddResidualBlock(CreateRelativePoseCost(r.T_a_b, r.sqrt_information), nullptr, x_a,
                              x_b);
  }
  if (offset != nullptr && problem->HasParameterBlock(offset)) {
    problem->AddResidualBlock(CreateOffsetPriorCost(options_.disparity_offset_prior_sigma_px),
                              nullptr, offset);
  }
  if (with_prior && !prior_.empty()) {
    std::map<KeyframeId, double*> block_of;
    for (KeyframeState& kf : window_) block_of[kf.id] = kf.x.data();
    std::vector<double*> blocks;
    for (KeyframeId id : prior_.keyframes) blocks.push_back(block_of.at(id));
    problem->AddResidualBlock(CreatePriorCost(prior_), nullptr, blocks);
  }
  return active;
}

ceres::Solver::Options SlidingWindowBa::SolverOptions() const {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
  solver_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  solver_options.max_num_iterations = options_.max_num_iterations;
  solver_options.max_solver_time_in_seconds =
      CeresSolverTimeLimit(options_.max_solver_time_in_seconds);
  solver_options.function_tolerance = options_.function_tolerance;
  solver_options.num_threads = options_.num_threads;
  solver_options.logging_type = ceres::SILENT;
  return solver_options;
}

double SlidingWindowBa::WindowSpan() const {
  double span = 0.0;
  for (const KeyframeState& a : window_) {
    for (const KeyframeState& b : window_) {
      const Eigen::Vector3d d = BlockToPose(a.x).translation() - BlockToPose(b.x).translation();
      span = std::max(span, d.norm());
    }
  }
  return span;
}

std::optional<double> SlidingWindowBa::EstimateOffsetAside() {
  // The window's state is saved, solved again with the offset free, and restored: the solve
  // starts where the main one ended, so it measures how far the offset would pull from there.
  std::vector<PoseBlock> poses;
  for (const KeyframeState& kf : window_) poses.push_back(kf.x);
  const auto counts = CountObservations();
  std::map<LandmarkId, Eigen::Vector3d> landmarks_before;
  for (const auto& [id, n] : counts) {
    if (IsActive(id, counts)) landmarks_before[id] = landmarks_.at(id);
  }
  auto manifold = MakePoseManifold();
  auto loss = MakeLoss(options_.loss, options_.loss_scale);
  ceres::Problem problem(BorrowingProblemOptions());
  double offset = K_.disparity_offset_px;
  int num_held_used = 0;
  // Without the marginalisation prior: it holds the scale the window had under the offset in
  // use, which would pull the estimate back toward that offset (a 40-keyframe window with a
  // 0.4 px offset: 0.33 px calibrated with the prior, 0.39 without;
  // SlidingWindowBaTest.EstimatesTheRigsDisparityOffset). The window's oldest keyframe holds
  // the gauge either way (IsHeldConstant).
  BuildProblem(counts, manifold.get(), loss.get(), &offset, /*with_prior=*/false, &problem,
               &num_held_used);
  std::optional<double> estimate;
  if (problem.HasParameterBlock(&offset)) {
    // From the main solve's optimum the offset's pull changes the cost by less than the main
    // solve's relative tolerance (1e-6), which would stop the solve before its first step.
    ceres::Solver::Options solver_options = SolverOptions();
    solver_options.function_tolerance = 1e-12;
    ceres::Solver::Summary ceres_summary;
    ceres::Solve(solver_options, &problem, &ceres_summary);
    if (ceres_summary.IsSolutionUsable()) estimate = offset;
  }
  for (size_t i = 0; i < window_.size(); ++i) window_[i].x = poses[i];
  for (const auto& [id, p_w] : landmarks_before) landmarks_[id] = p_w;
  return estimate;
}

SlidingWindowBa::Summary SlidingWindowBa::Optimize() {
  const auto t0 = std::chrono::steady_clock::now();
  Summary summary;
  summary.num_keyframes = static_cast<int>(window_.size());
  if (window_.empty()) return summary;
  InitializeMonoLandmarks();
  relative_priors_.erase(std::remove_if(relative_priors_.begin(), relative_priors_.end(),
                                        [&](const RelativePosePrior& r) {
                                          return BlockOf(r.a) == nullptr || BlockOf(r.b) == nullptr;
                                        }),
                         relative_priors_.end());

  auto manifold = MakePoseManifold();
  auto loss = MakeLoss(options_.loss, options_.loss_scale);
  std::set<LandmarkId> active_before;
  for (int round = 0;; ++round) {
    const auto counts = CountObservations();
    ceres::Problem problem(BorrowingProblemOptions());
    // The rig's disparity offset, estimated with the window (see Options).
    const bool estimate_offset = options_.estimate_disparity_offset && K_.is_stereo();
    double offset = K_.disparity_offset_px;
    const std::set<LandmarkId> active =
        BuildProblem(counts, manifold.get(), loss.get(), estimate_offset ? &offset : nullptr,
                     /*with_prior=*/true, &problem, &summary.num_held_keyframes);
    if (round == 0) active_before = active;
    summary.num_landmarks = static_cast<int>(active.size());
    summary.num_residual_blocks = problem.NumResidualBlocks();
    if (problem.NumResidualBlocks() == 0) {
      summary.usable = true;  // nothing to estimate yet: the state is trivially optimal.
      break;
    }

    const ceres::Solver::Options solver_options = SolverOptions();
    ceres::Solver::Summary ceres_summary;
    ceres::Solve(solver_options, &problem, &ceres_summary);
    VLOG(3) << ceres_summary.FullReport();
    ++summary.num_solves;
    summary.num_iterations += static_cast<int>(ceres_summary.iterations.size());
    if (round == 0) summary.initial_cost = ceres_summary.initial_cost;
    summary.final_cost = ceres_summary.final_cost;
    summary.usable = ceres_summary.IsSolutionUsable();
    if (estimate_offset && summary.usable) K_.disparity_offset_px = offset;

    int removed = 0;
    if (options_.remove_outliers && summary.usable) {
      for (auto* keyframes : {&window_, &held_}) {
        for (KeyframeState& kf : *keyframes) {
          auto& obs = kf.observations;
          const auto end = std::remove_if(obs.begin(), obs.end(), [&](const BaObservation& o) {
            if (!active.count(o.landmark)) return false;
            double depth = 0.0;
            const double e2 =
                WhitenedSquaredError(K_, o, kf.x.data(), landmarks_.at(o.landmark).data(), &depth);
            const double bound =
                ResidualDof(K_, o) == 3 ? kChi2Quantile95Dof3 : kChi2Quantile95Dof2;
            return e2 > bound || depth < options_.min_depth;
          });
          removed += static_cast<int>(obs.end() - end);
          obs.erase(end, obs.end());
        }
      }
    }
    summary.num_outliers_removed += removed;
    if (removed == 0 || round >= options_.max_outlier_rounds) break;
  }
  const auto counts = CountObservations();
  for (LandmarkId id : active_before) {
    if (!IsActive(id, counts)) ++summary.num_landmarks_culled;
  }
  if (options_.calibrate_disparity_offset && !options_.estimate_disparity_offset &&
      K_.is_stereo() && summary.usable && !offset_calibration_.converged() &&
      WindowSpan() >= options_.offset_calibration.min_window_span_baselines * K_.baseline) {
    const std::optional<double> estimate = EstimateOffsetAside();
    if (estimate) {
      offset_calibration_.Add(*estimate);
      K_.disparity_offset_px = offset_calibration_.offset_px();
      // The prior was linearised with the offset of its time: its scale is that offset's.
      if (std::abs(K_.disparity_offset_px - prior_offset_px_) >
          options_.offset_calibration.max_prior_offset_change_px) {
        DropPrior();
        prior_offset_px_ = K_.disparity_offset_px;
      }
      VLOG(2) << "disparity offset aside " << *estimate << " px, rig "
              << K_.disparity_offset_px << " px";
    }
  }
  summary.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

PoseOnlyResult SlidingWindowBa::TrackFrame(const std::vector<BaObservation>& observations,
                                           const Pose& T_w_c_guess,
                                           const PoseOnlyOptions& options) const {
  const auto counts = CountObservations();
  return EstimatePoseOnly(
      K_, observations,
      [&](LandmarkId id) -> std::optional<Eigen::Vector3d> {
        if (!IsActive(id, counts)) return std::nullopt;
        return landmarks_.at(id);
      },
      T_w_c_guess, options);
}

std::vector<KeyframeId> SlidingWindowBa::WindowKeyframes() const {
  std::vector<KeyframeId> ids;
  for (const KeyframeState& kf : window_) ids.push_back(kf.id);
  return ids;
}

std::vector<KeyframeId> SlidingWindowBa::HeldKeyframes() const {
  std::vector<KeyframeId> ids;
  for (const KeyframeState& kf : held_) ids.push_back(kf.id);
  return ids;
}

std::vector<KeyframeId> SlidingWindowBa::ObservingKeyframes(LandmarkId id) const {
  std::vector<KeyframeId> ids;
  for (const KeyframeState& kf : window_) {
    const auto& obs = kf.observations;
    if (std::any_of(obs.begin(), obs.end(),
                    [&](const BaObservation& o) { return o.landmark == id; })) {
      ids.push_back(kf.id);
    }
  }
  return ids;
}

std::optional<Pose> SlidingWindowBa::KeyframePose(KeyframeId id) const {
  for (const KeyframeState& kf : window_) {
    if (kf.id == id) return BlockToPose(kf.x);
  }
  return std::nullopt;
}

std::optional<Eigen::Vector3d> SlidingWindowBa::LandmarkPosition(LandmarkId id) const {
  const auto it = landmarks_.find(id);
  if (it == landmarks_.end()) return std::nullopt;
  return it->second;
}

std::map<LandmarkId, Eigen::Vector3d> SlidingWindowBa::Landmarks() const {
  std::map<LandmarkId, Eigen::Vector3d> out;
  for (const auto& [id, n] : CountObservations()) {
    const auto it = landmarks_.find(id);
    if (it != landmarks_.end()) out[id] = it->second;
  }
  return out;
}

}  // namespace dala
