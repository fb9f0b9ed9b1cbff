#ifndef DALA_TOOLS_BENCH_EVALUATE_RUN_H_
#define DALA_TOOLS_BENCH_EVALUATE_RUN_H_

// Turning a finished `dala run` into a row of results: the exit status, the timings and counts
// of its report.json, and the metrics of its trajectory.txt re-evaluated against the sequence's
// ground truth with core/eval Evaluate() (so the numbers do not depend on what `dala run`
// computed). Draws the run's plots.

#include <optional>
#include <string>
#include <vector>

#include "core/trajectory.h"
#include "tools/bench/run_result.h"
#include "tools/bench/subprocess.h"
#include "tools/bench/suite.h"

namespace dala::bench {

// The ground truth T_w_c0 of a sequence folder: poses.txt + times.txt when both are there
// (KITTI-like, and what `dala synth` writes), else OpenDataset(folder).ground_truth().
// Returns nullopt (and why) when the folder has none or cannot be read.
std::optional<Trajectory> LoadGroundTruth(const std::string& folder, std::string* why);

// Per-frame data kept beside each run (bench_series.json) for the per-sequence plots.
struct RunSeries {
  std::vector<double> frame, ms_total, ms_frontend, ms_estimator;  // From report.json.
  std::vector<double> distance_m, ate_m;  // ATE of every pair against the path travelled.
  std::string last_note;  // The last frame's "note" (e.g. "initialising: <reason>").
};

// Fills `result` (whose identity fields, command and run_dir are set) from the child's exit and
// the files in `run_dir_abs`; writes run_dir_abs/eval.png and timing.png and *series. Never
// throws on a bad run: the status and error say what went wrong.
void EvaluateRun(const BenchRun& run, const SubprocessResult& child, const std::string& run_dir_abs,
                 const std::optional<Trajectory>& ground_truth, const std::string& gt_why,
                 BenchRunResult* result, RunSeries* series);

nlohmann::json ToJson(const RunSeries& s);
RunSeries RunSeriesFromJson(const nlohmann::json& j);

// Linear-interpolation percentile (numpy's default), p in [0, 100]; nullopt for no values.
std::optional<double> Percentile(std::vector<double> values, double p);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_EVALUATE_RUN_H_
