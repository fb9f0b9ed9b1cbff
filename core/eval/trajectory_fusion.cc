#include "core/eval/trajectory_fusion.h"

#include <cmath>
#include <map>
#include <utility>

#include "core/geometry.h"

namespace dala {
namespace {

// Every stamp of every run: stamp -> (run index, pose), runs in order.
using PosesByStamp = std::map<int64_t, std::vector<std::pair<size_t, Pose>>>;

// The alignment of run k onto `mean` over the stamps both have.
bool AlignRun(const PosesByStamp& by_stamp, size_t k, const std::map<int64_t, Pose>& mean,
              const TrajectoryFusionOptions& options, Sim3Alignment* alignment, std::string* why) {
  std::vector<Eigen::Vector3d> p_run, p_mean;
  for (const auto& [t, poses] : by_stamp) {
    const auto m = mean.find(t);
    if (m == mean.end()) continue;
    for (const auto& [run, T_w_c] : poses) {
      if (run != k) continue;
      p_run.push_back(T_w_c.translation());
      p_mean.push_back(m->second.translation());
    }
  }
  if (static_cast<int>(p_run.size()) < options.min_common_stamps) {
    *why = "run " + std::to_string(k + 1) + " shares " + std::to_string(p_run.size()) +
           " stamps with the others (at least " + std::to_string(options.min_common_stamps) +
           " are needed to align it): are these runs of the same frames?";
    return false;
  }
  std::string alignment_why;
  if (!ComputeAlignment(p_run, p_mean, options.alignment, alignment, &alignment_why)) {
    *why = "run " + std::to_string(k + 1) + " cannot be aligned onto the others: " + alignment_why;
    return false;
  }
  return true;
}

// The per-stamp mean of the runs under `alignments`, with the count and spread per stamp.
std::map<int64_t, Pose> MeanOf(const PosesByStamp& by_stamp,
                               const std::vector<Sim3Alignment>& alignments,
                               std::map<int64_t, std::pair<int, double>>* count_spread) {
  std::map<int64_t, Pose> mean;
  for (const auto& [t, poses] : by_stamp) {
    Eigen::Vector3d p_sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d R_sum = Eigen::Matrix3d::Zero();
    std::vector<Eigen::Vector3d> positions;
    for (const auto& [run, T_w_c] : poses) {
      const Pose T = alignments[run].Apply(T_w_c);
      positions.push_back(T.translation());
      p_sum += T.translation();
      R_sum += T.linear();
    }
    const Eigen::Vector3d p = p_sum / static_cast<double>(positions.size());
    mean[t] = MakePose(NearestRotation(R_sum), p);
    if (count_spread != nullptr) {
      double sq = 0.0;
      for (const Eigen::Vector3d& q : positions) sq += (q - p).squaredNorm();
      (*count_spread)[t] = {static_cast<int>(positions.size()),
                            std::sqrt(sq / static_cast<double>(positions.size()))};
    }
  }
  return mean;
}

}  // namespace

bool TrajectoryFusionOptions::IsValid(std::string* why) const {
  if (iterations < 1) {
    *why = "iterations must be >= 1";
    return false;
  }
  if (min_common_stamps < 3) {
    *why = "min_common_stamps must be >= 3 (an alignment needs 3 positions)";
    return false;
  }
  return true;
}

bool FuseTrajectories(const std::vector<Trajectory>& runs, const TrajectoryFusionOptions& options,
                      FusedTrajectory* fused, std::string* why) {
  if (!options.IsValid(why)) return false;
  if (runs.empty()) {
    *why = "no run to fuse";
    return false;
  }
  for (size_t k = 0; k < runs.size(); ++k) {
    if (runs[k].empty()) {
      *why = "run " + std::to_string(k + 1) + " has no pose";
      return false;
    }
    if (runs[k].has_timestamps != runs[0].has_timestamps) {
      *why = "run " + std::to_string(k + 1) + (runs[k].has_timestamps ? " has" : " has no") +
             " timestamps and run 1" + (runs[0].has_timestamps ? " has" : " has no") +
             ": give every run in the same format";
      return false;
    }
  }
  PosesByStamp by_stamp;
  for (size_t k = 0; k < runs.size(); ++k) {
    for (const StampedPose& p : runs[k].poses) by_stamp[p.t_ns].emplace_back(k, p.T_w_c);
  }
  // Start: the first run is the mean; then align every run onto the mean and average again.
  std::map<int64_t, Pose> mean;
  for (const StampedPose& p : runs[0].poses) mean[p.t_ns] = p.T_w_c;
  std::vector<Sim3Alignment> alignments(runs.size());
  for (int round = 0; round < options.iterations; ++round) {
    for (size_t k = 0; k < runs.size(); ++k) {
      if (!AlignRun(by_stamp, k, mean, options, &alignments[k], why)) return false;
    }
    mean = MeanOf(by_stamp, alignments, nullptr);
  }
  // Into the first run's world: the mean aligned onto it, and every run's alignment with it.
  std::vector<Eigen::Vector3d> p_mean, p_first;
  for (const StampedPose& p : runs[0].poses) {
    p_mean.push_back(mean.at(p.t_ns).translation());
    p_first.push_back(p.T_w_c.translation());
  }
  Sim3Alignment into_first;
  if (runs[0].size() >= 3 &&
      !ComputeAlignment(p_mean, p_first, options.alignment, &into_first, why)) {
    return false;
  }
  for (Sim3Alignment& a : alignments) {
    // p -> into_first(a(p)) = s_f R_f (s_a R_a p + t_a) + t_f.
    Sim3Alignment composed;
    composed.scale = into_first.scale * a.scale;
    composed.T_g_e.linear() = into_first.T_g_e.linear() * a.T_g_e.linear();
    composed.T_g_e.translation() = into_first.Apply(a.T_g_e.translation());
    a = composed;
  }
  std::map<int64_t, std::pair<int, double>> count_spread;
  mean = MeanOf(by_stamp, alignments, &count_spread);
  *fused = FusedTrajectory();
  fused->trajectory.has_timestamps = runs[0].has_timestamps;
  for (const auto& [t, T_w_c] : mean) {
    fused->trajectory.Add(t, T_w_c);
    fused->runs.push_back(count_spread.at(t).first);
    fused->spread.push_back(count_spread.at(t).second);
  }
  fused->alignments = alignments;
  return true;
}

}  // namespace dala
