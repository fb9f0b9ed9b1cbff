#include "backend/system_ensemble.h"

#include <algorithm>
#include <chrono>
#include <exception>

#include "core/error.h"

namespace dala {

bool SystemEnsembleOptions::IsValid(std::string* why) const {
  if (draws < 1) {
    *why = "draws must be >= 1, not " + std::to_string(draws);
    return false;
  }
  if (threads < 1) {
    *why = "threads must be >= 1, not " + std::to_string(threads);
    return false;
  }
  return true;
}

SystemEnsemble::SystemEnsemble(const StereoRig& rig, const SystemOptions& options,
                               const SystemEnsembleOptions& ensemble) {
  std::string why;
  if (!ensemble.IsValid(&why)) throw Error() << "invalid ensemble options: " << why;
  for (int k = 0; k < ensemble.draws; ++k) {
    SystemOptions draw_options = options;
    draw_options.ransac_order_seed = options.ransac_order_seed + static_cast<uint64_t>(k);
    // The stereo motion's P3P RANSAC draws from its own generator.
    draw_options.frontend.motion.seed = options.frontend.motion.seed + static_cast<uint64_t>(k);
    draws_.push_back(std::make_unique<System>(rig, draw_options));
  }
  workers_.resize(std::min(ensemble.threads, ensemble.draws) - 1);
}

template <typename Task>
void SystemEnsemble::ForEachDraw(const Task& task) {
  const int threads = static_cast<int>(workers_.size()) + 1;
  std::vector<std::exception_ptr> errors(draws_.size());
  const auto run_thread = [&](int t) {
    for (int k = t; k < size(); k += threads) {
      try {
        task(k);
      } catch (...) {
        errors[k] = std::current_exception();
      }
    }
  };
  int started = 0;
  try {
    for (int t = 1; t < threads; ++t, ++started) {
      workers_[t - 1].Start([&run_thread, t] { run_thread(t); });
    }
  } catch (...) {
    // A worker that cannot start (no thread): the started ones still use this frame's locals.
    for (int t = 0; t < started; ++t) workers_[t].Wait();
    throw;
  }
  run_thread(0);
  for (WorkerThread& w : workers_) w.Wait();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

TrackResult SystemEnsemble::Track(const Frame& frame) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<TrackResult> results(draws_.size());
  if (draws_.size() == 1) {
    results[0] = draws_[0]->Track(frame);
  } else {
    const FrameFeatures features =
        ComputeFrameFeatures(frame, first().rig(), first().options().frontend,
                             workers_.empty() ? nullptr : &workers_[0]);
    ForEachDraw([&](int k) { results[k] = draws_[k]->Track(frame, features); });
  }
  wall_ms_.push_back(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  return results.front();
}

void SystemEnsemble::SkipFrame(FrameId frame, int64_t t_ns, const std::string& note) {
  for (auto& draw : draws_) draw->SkipFrame(frame, t_ns, note);
}

void SystemEnsemble::UseMap(const SavedMap& map) {
  for (auto& draw : draws_) draw->UseMap(map);
}

std::vector<RefinementSummary> SystemEnsemble::Finish(const std::function<bool()>& stop_requested) {
  std::vector<RefinementSummary> summaries(draws_.size());
  ForEachDraw([&](int k) { summaries[k] = draws_[k]->Finish(stop_requested); });
  return summaries;
}

std::vector<Trajectory> SystemEnsemble::Trajectories() const {
  std::vector<Trajectory> trajectories;
  for (const auto& draw : draws_) trajectories.push_back(draw->trajectory());
  return trajectories;
}

AlignmentType SystemEnsemble::FusionAlignment() const {
  return first().IsMetric() ? AlignmentType::kSE3 : AlignmentType::kSim3;
}

std::vector<int> SystemEnsemble::FusableDraws(const std::vector<Trajectory>& trajectories) const {
  const size_t alignment_poses = TrajectoryFusionOptions().min_common_stamps;
  std::vector<int> draws;
  for (size_t k = 0; k < trajectories.size(); ++k) {
    if (trajectories[k].size() >= alignment_poses) draws.push_back(static_cast<int>(k));
  }
  return draws;
}

bool SystemEnsemble::Fuse(const std::vector<Trajectory>& trajectories,
                          const std::vector<int>& draws, FusedTrajectory* fused,
                          std::string* why) const {
  if (draws.empty()) {
    *why = "no draw to fuse";
    return false;
  }
  std::vector<Trajectory> runs;
  for (int k : draws) runs.push_back(trajectories.at(k));
  TrajectoryFusionOptions options;
  options.alignment = FusionAlignment();
  if (FuseTrajectories(runs, options, fused, why)) return true;
  // FuseTrajectories counts its runs from 1: name them by their seeds.
  std::string seeds;
  for (size_t i = 0; i < draws.size(); ++i) {
    seeds += (i > 0 ? ", " : "") + std::to_string(seed(draws[i]));
  }
  *why = "the draws of seeds " + seeds + " (runs 1-" + std::to_string(draws.size()) +
         " in that order): " + *why;
  return false;
}

}  // namespace dala
