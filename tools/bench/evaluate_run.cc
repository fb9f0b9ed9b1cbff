#include "tools/bench/evaluate_run.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/eval/evaluate.h"
#include "core/eval/plot.h"
#include "core/io/dataset.h"
#include "core/io/trajectory_io.h"
#include "tools/bench/line_chart.h"

namespace dala::bench {
namespace fs = std::filesystem;
namespace {

std::optional<double> NumberAt(const nlohmann::json& j, std::initializer_list<const char*> path) {
  const nlohmann::json* node = &j;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key)) return std::nullopt;
    node = &node->at(key);
  }
  if (!node->is_number()) return std::nullopt;
  return node->get<double>();
}

std::optional<int> IntAt(const nlohmann::json& j, std::initializer_list<const char*> path) {
  const std::optional<double> v = NumberAt(j, path);
  if (!v) return std::nullopt;
  return static_cast<int>(*v);
}

void AppendError(BenchRunResult* r, const std::string& text) {
  r->error += (r->error.empty() ? "" : "; ") + text;
}

// Reads report.json: per-frame times and the summary counts. False (with the reason in the
// result's error) when it is missing or not JSON.
bool ReadReport(const std::string& path, BenchRunResult* r, RunSeries* series) {
  std::ifstream is(path);
  if (!is) {
    AppendError(r, "no report.json");
    return false;
  }
  nlohmann::json report;
  try {
    report = nlohmann::json::parse(is);
  } catch (const nlohmann::json::exception& e) {
    AppendError(r, std::string("report.json is not JSON: ") + e.what());
    return false;
  }
  int lost = 0;
  if (report.contains("frames") && report["frames"].is_array()) {
    for (const nlohmann::json& f : report["frames"]) {
      // `dala run --draws`: the wall time of every draw is the run's time for the frame.
      const std::optional<double> total = NumberAt(f, {"ms", "all_draws"})
                                              ? NumberAt(f, {"ms", "all_draws"})
                                              : NumberAt(f, {"ms", "total"});
      if (f.contains("status") && f["status"] == "lost") ++lost;
      if (!total) continue;
      series->frame.push_back(NumberAt(f, {"frame"}).value_or(series->frame.size()));
      series->ms_total.push_back(*total);
      series->ms_frontend.push_back(NumberAt(f, {"ms", "frontend"}).value_or(std::nan("")));
      series->ms_estimator.push_back(NumberAt(f, {"ms", "estimator"}).value_or(std::nan("")));
    }
    r->frames = static_cast<int>(report["frames"].size());
    if (!report["frames"].empty() && report["frames"].back().contains("note") &&
        report["frames"].back()["note"].is_string()) {
      series->last_note = report["frames"].back()["note"].get<std::string>();
    }
  }
  r->ms_median = Percentile(series->ms_total, 50.0);
  r->ms_p95 = Percentile(series->ms_total, 95.0);
  if (!series->ms_total.empty()) {
    r->ms_max = *std::max_element(series->ms_total.begin(), series->ms_total.end());
  }
  if (const auto frames = IntAt(report, {"summary", "frames"})) r->frames = frames;
  r->fps = NumberAt(report, {"summary", "fps"});
  r->landmarks = IntAt(report, {"summary", "landmarks"});
  r->keyframes = IntAt(report, {"summary", "keyframes"});
  r->keyframes_in_map = IntAt(report, {"summary", "keyframes_in_map"});
  if (r->keyframes_in_map && *r->keyframes_in_map < 0) r->keyframes_in_map.reset();
  r->disparity_offset_px = NumberAt(report, {"summary", "disparity_offset_px"});
  r->tracking_failures = IntAt(report, {"summary", "tracking_failures"});
  if (!r->tracking_failures && r->frames) r->tracking_failures = lost;
  return true;
}

void DrawTiming(const BenchRun& run, const RunSeries& s, const std::string& png) {
  std::vector<ChartSeries> lines;
  lines.push_back({"total", s.frame, s.ms_total});
  if (std::any_of(s.ms_frontend.begin(), s.ms_frontend.end(), [](double v) { return v == v; })) {
    lines.push_back({"frontend", s.frame, s.ms_frontend});
  }
  if (std::any_of(s.ms_estimator.begin(), s.ms_estimator.end(), [](double v) { return v == v; })) {
    lines.push_back({"estimator", s.frame, s.ms_estimator});
  }
  LineChartOptions options;
  options.title = "per-frame time: " + run.key();
  options.x_label = "frame";
  options.y_label = "time [ms]";
  DrawLineChart(lines, options, png);
}

}  // namespace

std::optional<double> Percentile(std::vector<double> values, double p) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  const double pos = p / 100.0 * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

std::optional<Trajectory> LoadGroundTruth(const std::string& folder, std::string* why) {
  try {
    const fs::path poses = fs::path(folder) / "poses.txt";
    const fs::path times = fs::path(folder) / "times.txt";
    if (fs::is_regular_file(poses) && fs::is_regular_file(times)) {
      Trajectory gt = ReadTrajectory(poses.string(), TrajectoryFormat::kKitti);
      ApplyTimes(times.string(), &gt);
      return gt;
    }
    const std::unique_ptr<Dataset> dataset = OpenDataset(folder);
    if (dataset->ground_truth()) return *dataset->ground_truth();
    *why = folder + " has no ground truth";
  } catch (const Error& e) {
    *why = std::string("ground truth of ") + folder + ": " + e.what();
  }
  return std::nullopt;
}

void EvaluateRun(const BenchRun& run, const SubprocessResult& child, const std::string& run_dir_abs,
                 const std::optional<Trajectory>& ground_truth, const std::string& gt_why,
                 BenchRunResult* r, RunSeries* series) {
  r->wall_s = child.wall_s;
  r->peak_rss_mb = child.peak_rss_mb;
  const std::string log = run_dir_abs + "/log.txt";
  if (!child.started) {
    r->status = kStatusFailed;
    r->error = "could not start: " + child.error;
    return;
  }
  if (child.timed_out) {
    r->status = kStatusTimeout;
    r->signal = child.signal;
    char buf[64];
    std::snprintf(buf, sizeof(buf), "killed after the timeout (%.0f s)", child.wall_s);
    r->error = buf;
    return;
  }
  if (child.signaled) {
    r->status = kStatusCrashed;
    r->signal = child.signal;
    r->error =
        "killed by signal " + std::to_string(child.signal) + " (" + strsignal(child.signal) + ")";
    const std::string tail = TailOfFile(log, 3);
    if (!tail.empty()) r->error += ": " + tail;
    return;
  }
  r->exit_code = child.exit_code;
  if (child.exit_code != 0) {
    const std::string tail = TailOfFile(log);
    std::string lower = tail;
    std::transform(lower.begin(), lower.end(), lower.begin(), ::tolower);
    const bool unsupported =
        child.exit_code == 2 && (lower.find("not supported") != std::string::npos ||
                                 lower.find("unsupported") != std::string::npos);
    r->status = unsupported ? kStatusUnsupported : kStatusFailed;
    r->error = "exit status " + std::to_string(child.exit_code) + (tail.empty() ? "" : ": " + tail);
    return;
  }
  // Exit 0: the run must have left its report and trajectory.
  const bool have_report = ReadReport(run_dir_abs + "/report.json", r, series);
  const std::string traj = run_dir_abs + "/trajectory.txt";
  if (!have_report || !fs::is_regular_file(traj)) {
    r->status = kStatusFailed;
    if (!fs::is_regular_file(traj)) AppendError(r, "no trajectory.txt");
    r->error = "exit status 0 but " + r->error;
    return;
  }
  r->status = kStatusOk;
  if (!series->ms_total.empty()) {
    try {
      DrawTiming(run, *series, run_dir_abs + "/timing.png");
      r->plot_timing = r->run_dir + "/timing.png";
    } catch (const Error& e) {
      AppendError(r, e.what());
    }
  }
  if (!ground_truth) {
    AppendError(r, gt_why);
    return;
  }

  Trajectory est;
  try {
    est = ReadTrajectory(traj, TrajectoryFormat::kTum);
  } catch (const Error& e) {
    r->status = kStatusFailed;
    // A monocular run that never initialised has no pose to evaluate: say why, not just that.
    if (series->last_note.rfind("initialising: ", 0) == 0) {
      AppendError(r, "no frame has a pose, the monocular map never started; last frame: " +
                         series->last_note);
    } else {
      AppendError(r, e.what());
    }
    return;
  }
  // SE(3) for stereo (metric scale observable), Sim(3) for monocular (scale free). RPE over 1
  // and 10 frames: defined for any sequence longer than 10 frames whatever its speed.
  EvalOptions options;
  options.alignment = run.config.mode == "mono" ? AlignmentType::kSim3 : AlignmentType::kSE3;
  r->alignment = run.config.mode == "mono" ? "sim3" : "se3";
  options.rpe_delta = 1.0;
  options.rpe_delta_unit = DeltaUnit::kFrames;
  const EvalResult e1 = Evaluate(*ground_truth, est, options);
  if (!e1.ok) {
    AppendError(r, "evaluation: " + e1.error);
    return;
  }
  // The second pass evaluates the aligned estimate without further alignment: RPE over 10
  // frames, and the KITTI segment errors, which are invariant to a rigid transform (stereo: the
  // same as on the raw estimate) but not to scale (mono: those of the Sim(3)-scaled estimate,
  // as monocular results are reported).
  const Trajectory aligned = AlignTrajectory(est, e1.alignment);
  options.alignment = AlignmentType::kNone;
  options.rpe_delta = 10.0;
  const EvalResult e10 = Evaluate(*ground_truth, aligned, options);
  r->pairs = static_cast<int>(e1.pairs.size());
  r->path_length_m = e1.gt_path_length_m;
  r->ate_rmse = e1.ate.translation.rmse;
  r->ate_mean = e1.ate.translation.mean;
  r->ate_median = e1.ate.translation.median;
  r->ate_max = e1.ate.translation.max;
  r->scale = e1.alignment.scale;
  if (e1.has_rpe) {
    r->rpe_trans = e1.rpe.translation.rmse;
    r->rpe_rot_deg = e1.rpe.rotation_deg.rmse;
  }
  if (e10.ok && e10.has_rpe) {
    r->rpe10_trans = e10.rpe.translation.rmse;
    r->rpe10_rot_deg = e10.rpe.rotation_deg.rmse;
  }
  if (e10.ok && e10.has_kitti) {
    r->t_err_percent = e10.kitti.t_err_percent;
    r->r_err_deg_per_100m = e10.kitti.r_err_deg_per_100m;
  }
  series->distance_m = e1.pair_distance_m;
  series->ate_m = e1.ate.translation_errors;
  try {
    PlotEvaluation(*ground_truth, aligned, e1, run_dir_abs + "/eval.png");
    r->plot_trajectory = r->run_dir + "/eval.png";
  } catch (const Error& e) {
    AppendError(r, e.what());
  }
}

nlohmann::json ToJson(const RunSeries& s) {
  const auto clean = [](const std::vector<double>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (double x : v) a.push_back(std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr));
    return a;
  };
  return {{"frame", clean(s.frame)},
          {"ms_total", clean(s.ms_total)},
          {"ms_frontend", clean(s.ms_frontend)},
          {"ms_estimator", clean(s.ms_estimator)},
          {"distance_m", clean(s.distance_m)},
          {"ate_m", clean(s.ate_m)}};
}

RunSeries RunSeriesFromJson(const nlohmann::json& j) {
  const auto read = [&](const char* key) {
    std::vector<double> v;
    if (j.contains(key) && j[key].is_array()) {
      for (const auto& x : j[key]) v.push_back(x.is_number() ? x.get<double>() : std::nan(""));
    }
    return v;
  };
  RunSeries s;
  s.frame = read("frame");
  s.ms_total = read("ms_total");
  s.ms_frontend = read("ms_frontend");
  s.ms_estimator = read("ms_estimator");
  s.distance_m = read("distance_m");
  s.ate_m = read("ate_m");
  return s;
}

}  // namespace dala::bench
