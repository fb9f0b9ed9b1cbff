// `dala run`: offline trajectory reconstruction over a dataset folder.
#include <gflags/gflags.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <sstream>
#include <thread>

#include "backend/system.h"
#include "backend/system_ensemble.h"
#include "core/error.h"
#include "core/eval/alignment.h"
#include "core/eval/evaluate.h"
#include "core/eval/plot.h"
#include "core/eval/scale_along_path.h"
#include "core/eval/statistics.h"
#include "core/io/atomic_file.h"
#include "core/io/dataset.h"
#include "core/io/ply_writer.h"
#include "core/io/trajectory_io.h"
#include "tools/bench/line_chart.h"
#include "tools/command.h"
#include "tools/process_memory.h"
#include "tools/report/frame_video.h"
#include "tools/report/report_data.h"
#include "tools/report/report_html.h"
#include "tools/stop_signal.h"

DECLARE_string(out);  // tools/common_flags.cc
DECLARE_double(fps);     // tools/common_flags.cc
DECLARE_string(times);  // tools/common_flags.cc
DECLARE_string(right_folder);   // tools/common_flags.cc
DECLARE_string(stereo_layout);  // tools/common_flags.cc
DEFINE_string(config, "", "run: YAML file of options (--dump_config prints them; docs/options.md)");
DEFINE_string(estimator, "", "run: ba (sliding-window bundle adjustment) or ekf (overrides config)");
DEFINE_string(mode, "", "run: stereo or mono (overrides config)");
DEFINE_string(format, "auto",
              "run: dataset format: auto, kitti, euroc, tum, synthetic, images, video, bag");
DEFINE_string(calibration, "",
              "run: calibration file (OpenCV, ROS camera_info, Kalibr camchain or dala YAML): "
              "required for an image folder or a video, overrides KITTI's and TUM's");
DEFINE_string(topic, "", "run: image topic of a ROS bag (empty: its only one)");
DEFINE_string(right_topic, "", "run: right camera's image topic of a ROS bag (stereo)");
DEFINE_string(ground_truth, "",
              "run: ground truth of an image folder or video (TUM by time, KITTI by frame)");
DEFINE_int32(first_frame, 0, "run: index of the first frame to process");
DEFINE_int32(max_frames, 0, "run: process at most this many frames (0: all)");
DEFINE_bool(dump_config, false,
            "run: print the effective options users tune as YAML and exit (docs/options.md)");
DEFINE_bool(dump_config_all, false,
            "run: as --dump_config, with the experimental (study) options too");
DEFINE_bool(progress, true, "run: show progress on stderr");
DEFINE_bool(strict, false,
            "run: stop with an error (exit 2) at a missing, unreadable or wrongly sized image "
            "instead of skipping its frame");

DEFINE_string(video, "",
              "run: also write FILE.mp4, a video of what the frontend saw: each frame with its "
              "tracked points by track age, stereo matches, state, keyframe flag and the path so "
              "far from above (docs/pipeline.md; off when empty)");

DEFINE_int32(draws, 1,
             "run: run the pipeline N times over the frames, with the RANSAC draws "
             "ransac_order_seed + 0..N-1, and write their fused trajectory (docs/evaluation.md, "
             "\"Several draws in one run\"); N times the work");
DEFINE_int32(threads, 0, "run: threads that step the --draws (0: one per core, at most N)");

DEFINE_string(map, "",
              "run: start in the saved map FILE (the map.dmap of an earlier run): frames are "
              "relocalised in it until one is placed, and the run continues in its frame");

// --set may be given several times: a validator collects every value.
static std::vector<std::string>& SetAssignments() {
  static std::vector<std::string> values;
  return values;
}
static bool CollectSet(const char*, const std::string& value) {
  if (!value.empty()) SetAssignments().push_back(value);
  return true;
}
DEFINE_string(set, "", "run: override one option, section.key=value (repeatable), e.g. "
                       "--set ba.window_size=10");
DEFINE_validator(set, &CollectSet);

namespace dala {
namespace {

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

class Progress {
 public:
  Progress(size_t total, bool enabled) : total_(total), enabled_(enabled), tty_(isatty(2)) {}
  void Update(size_t done, double fps, TrackingStatus status) {
    if (!enabled_) return;
    if (tty_) {
      const int width = 30;
      const int filled = total_ ? static_cast<int>(width * done / total_) : 0;
      std::cerr << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] "
                << done << "/" << total_ << "  " << std::fixed << std::setprecision(1) << fps
                << " fps  " << TrackingStatusName(status) << "   " << std::flush;
    } else if (done % 50 == 0 || done == total_) {
      std::cerr << "[run] frame " << done << "/" << total_ << ", " << std::fixed
                << std::setprecision(1) << fps << " fps, " << TrackingStatusName(status) << "\n";
    }
  }
  void Done() {
    if (enabled_ && tty_) std::cerr << "\n";
  }
  // A line of its own, also below a progress bar.
  void Say(const std::string& message) { std::cerr << (enabled_ && tty_ ? "\n" : "") << message; }

 private:
  size_t total_;
  bool enabled_, tty_;
};

// A value, or null when there is none.
nlohmann::json JsonOrNull(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

nlohmann::json FrameJson(const FrameStats& s) {
  return {{"frame", s.frame.value},
          {"t", SecondsFromNs(s.t_ns)},
          {"status", TrackingStatusName(s.status)},
          {"valid", s.valid},
          {"skipped", s.skipped},
          {"keyframe", s.keyframe},
          {"places", s.places},
          {"keyframes_in_map", s.keyframes_in_map},
          // The stereo rig's disparity offset in use (px; null: the estimator has none).
          {"disparity_offset_px", JsonOrNull(s.disparity_offset_px)},
          {"features", s.features},
          {"tracked", s.tracked},
          {"landmarks", s.landmarks},
          {"loop", s.loop},
          {"loop_closed", s.loop_closed},
          // The old keyframe's frame of the place recognised (null: no loop).
          {"loop_old_frame",
           s.loop_old_frame ? nlohmann::json(s.loop_old_frame->value) : nlohmann::json(nullptr)},
          // Why the estimator did not close the frame's loop (null: closed, or no loop judged).
          {"loop_not_closed",
           s.loop_not_closed.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.loop_not_closed)},
          {"note", s.note},
          {"ms",
           {{"detect", s.frontend.detect_ms},
            {"stereo", s.frontend.stereo_ms},
            {"track_motion", s.frontend.motion_ms},
            {"reacquire", s.frontend.track_ms},
            {"loop", s.frontend.loop_ms},
            {"frontend", s.frontend.total_ms},
            {"estimator", s.estimator_ms},
            {"total", s.total_ms}}}};
}

// One stage's percentiles (median, p95, max) over the frames processed (not the skipped ones).
nlohmann::json StageTable(const std::vector<FrameStats>& stats) {
  const auto column = [&](auto get) {
    std::vector<double> v;
    for (const FrameStats& s : stats) {
      if (!s.skipped) v.push_back(get(s));
    }
    return nlohmann::json{{"median", Percentile(v, 0.5)},
                          {"p95", Percentile(v, 0.95)},
                          {"max", v.empty() ? 0.0 : *std::max_element(v.begin(), v.end())}};
  };
  return {{"detect", column([](const FrameStats& s) { return s.frontend.detect_ms; })},
          {"stereo", column([](const FrameStats& s) { return s.frontend.stereo_ms; })},
          {"track_motion", column([](const FrameStats& s) { return s.frontend.motion_ms; })},
          {"reacquire", column([](const FrameStats& s) { return s.frontend.track_ms; })},
          {"loop", column([](const FrameStats& s) { return s.frontend.loop_ms; })},
          {"frontend", column([](const FrameStats& s) { return s.frontend.total_ms; })},
          {"estimator", column([](const FrameStats& s) { return s.estimator_ms; })},
          {"total", column([](const FrameStats& s) { return s.total_ms; })}};
}

// Reading the flags: the options (--config, --estimator, --mode, --set), then the dataset's.
SystemOptions OptionsFromFlags() {
  SystemOptions options;
  if (!FLAGS_config.empty()) LoadSystemOptions(FLAGS_config, &options);
  if (!FLAGS_estimator.empty()) SetSystemOption("estimator=" + FLAGS_estimator, &options);
  if (!FLAGS_mode.empty()) SetSystemOption("mode=" + FLAGS_mode, &options);
  for (const std::string& a : SetAssignments()) SetSystemOption(a, &options);
  return options;
}

DatasetOptions DatasetOptionsFromFlags(const SystemOptions& options) {
  DatasetOptions dataset_options;
  dataset_options.format = ParseDatasetFormat(FLAGS_format);
  dataset_options.calibration_yaml = FLAGS_calibration;
  dataset_options.right_folder = FLAGS_right_folder;
  dataset_options.times_file = FLAGS_times;
  dataset_options.fps = FLAGS_fps;
  dataset_options.stereo_layout = FLAGS_stereo_layout;
  dataset_options.ground_truth = FLAGS_ground_truth;
  dataset_options.topic = FLAGS_topic;
  dataset_options.right_topic = FLAGS_right_topic;
  dataset_options.first_frame = FLAGS_first_frame;
  dataset_options.max_frames = FLAGS_max_frames;
  dataset_options.allow_missing_images = !FLAGS_strict;
  // Mode "mono" is one camera: the right images are not even read.
  dataset_options.force_mono = options.mode == "mono" && !options.mono_stereo_motion;
  std::string why;
  if (!dataset_options.IsValid(&why)) throw Error() << why;
  return dataset_options;
}

// Running: every frame through the System (a frame whose image cannot be used is skipped unless
// --strict), until the end or a stop signal; then the global refinement.
struct FramesRun {
  size_t done = 0;
  int signal = 0;  // The stop signal received (0: none, the run reached the end).
  double wall_s = 0.0;
  std::vector<double> rss_mb;  // Resident memory after each frame (report.json, memory.png).
};

FramesRun TrackEveryFrame(Dataset* dataset, SystemEnsemble* runs, const StopSignal& stop,
                          report::FrameVideo* video) {
  FramesRun run;
  Progress progress(dataset->size(), FLAGS_progress);
  const auto start = std::chrono::steady_clock::now();
  Frame frame;
  int skipped_so_far = 0;
  TrackResult last;
  while (!stop.received()) {
    try {
      if (!dataset->Next(&frame)) break;
      last = runs->Track(frame);
      if (video != nullptr) {
        video->Add(frame.left, runs->first().last_measurement(), runs->first().stats().back(),
                   last.valid ? std::optional<Pose>(last.T_w_c) : std::nullopt);
      }
    } catch (const FrameError& e) {
      if (FLAGS_strict) throw;
      if (runs->first().stats().empty()) {
        throw Error() << e.message() << "; the first frame of the run cannot be skipped: "
                      << "restore it, or start after it with --first_frame " << e.frame().value + 1;
      }
      // A folder that lacks hundreds of frames (a partial copy) gets a few lines, not hundreds.
      constexpr int kSkipWarnings = 10;
      if (++skipped_so_far <= kSkipWarnings) {
        progress.Say("[run] warning: frame " + std::to_string(e.frame().value) +
                     " skipped (reported lost; --strict stops instead): " + e.message() + "\n");
      } else if (skipped_so_far == kSkipWarnings + 1) {
        progress.Say("[run] warning: more frames skipped, not listed here (report.json marks "
                     "every one \"skipped\")\n");
      }
      runs->SkipFrame(e.frame(), e.t_ns(), "skipped: " + e.message());
      last.status = TrackingStatus::kLost;
    }
    ++run.done;
    run.rss_mb.push_back(ResidentMemoryMb());
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.Update(run.done, run.done / std::max(elapsed, 1e-9), last.status);
  }
  progress.Done();
  run.signal = stop.received();
  if (run.signal != 0) {
    std::cerr << "[run] " << StopSignalName(run.signal) << ": stopped after " << run.done
              << " of " << dataset->size() << " frames; writing the results of those frames\n";
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

// The global refinement of the whole run, every draw (the BA estimator's global bundle
// adjustment, ba.final_ba); not after an interruption: the user asked to stop. A stop signal
// during it ends it (the estimates stay as without it; RefinementSummary::stopped) and counts as
// an interruption (run->signal).
std::vector<RefinementSummary> Refine(SystemEnsemble* runs, FramesRun* run,
                                      const SystemOptions& options, const StopSignal& stop) {
  if (run->signal != 0) {
    RefinementSummary refinement;
    refinement.report = "not run: the run was interrupted";
    return std::vector<RefinementSummary>(runs->size(), refinement);
  }
  // The global BA can take minutes on a long run (docs/backend.md): it is announced when it
  // starts, which is when it first polls the stop request (before its first solve).
  std::once_flag announced;
  std::vector<RefinementSummary> refinements = runs->Finish([&stop, &announced] {
    std::call_once(announced, [] {
      std::cerr << "[run] global BA after the last frame: Ctrl-C stops it and keeps the "
                   "trajectory without it\n";
    });
    return stop.received() != 0;
  });
  run->signal = stop.received();
  if (options.estimator == "ba") {
    for (int k = 0; k < runs->size(); ++k) {
      std::cerr << "[run] ";
      if (runs->size() > 1) std::cerr << "draw " << runs->seed(k) << ": ";
      std::cerr << refinements[k].report;
      if (refinements[k].done) std::cerr << ", " << refinements[k].time_s << " s";
      std::cerr << "\n";
    }
  }
  return refinements;
}

// DIR/draws holds the trajectory of each draw of this run (--draws N > 1) and nothing else: the
// files of an earlier run into the same folder (other seeds, or no --draws) are removed before
// anything is written.
void PrepareDrawsFolder(const std::string& dir, int draws) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(dir) / "draws";
  std::error_code error;
  if (fs::is_directory(folder)) {
    for (const fs::directory_entry& e : fs::directory_iterator(folder)) {
      const std::string name = e.path().filename().string();
      if (name.rfind("seed_", 0) == 0 && e.path().extension() == ".txt")
        fs::remove(e.path(), error);
    }
    if (draws == 1) fs::remove(folder, error);  // Only when empty.
  }
  if (draws > 1) CreateDirectories(folder.string());
}

// How a run is evaluated against its ground truth: by a similarity for one camera (its unit is
// its own), rigidly otherwise.
AlignmentType EvaluationAlignment(const SystemOptions& options) {
  return options.mode == "mono" ? AlignmentType::kSim3 : AlignmentType::kSE3;
}

// --draws N: the trajectory written is the draws' fusion (SystemEnsemble::Fuse), in the world
// and unit of the first draw that has one (the reference: its map, report and per-frame
// statistics are the ones written).
struct DrawsResult {
  int reference = 0;
  std::vector<int> fused_draws;  // The draws fused (with a pose at 3 frames or more).
  FusedTrajectory fused;
  std::string not_fused;  // Why the draws could not be fused (empty: fused, or one draw).
  Trajectory trajectory, online_trajectory;

  // The trajectory written is a fusion of two draws or more.
  bool fused_several() const { return not_fused.empty() && fused_draws.size() > 1; }
};

// `refined`: a global refinement ran, so the online trajectories differ from the final ones.
DrawsResult FuseDraws(const SystemEnsemble& runs, const std::vector<Trajectory>& final_runs,
                      const std::vector<Trajectory>& online_runs, bool refined) {
  DrawsResult r;
  r.fused_draws = runs.FusableDraws(final_runs);
  if (!r.fused_draws.empty()) r.reference = r.fused_draws.front();
  r.trajectory = final_runs[r.reference];
  r.online_trajectory = online_runs[r.reference];
  if (runs.size() == 1 || r.fused_draws.size() < 2) return r;
  if (!runs.Fuse(final_runs, r.fused_draws, &r.fused, &r.not_fused)) {
    r.fused_draws = {r.reference};
    return r;
  }
  r.trajectory = r.fused.trajectory;
  if (!refined) {
    r.online_trajectory = r.trajectory;  // The same trajectories: the same fusion.
    return r;
  }
  FusedTrajectory online;
  std::string why;
  if (runs.Fuse(online_runs, r.fused_draws, &online, &why)) {
    r.online_trajectory = online.trajectory;
  } else {
    std::cerr << "[run] warning: the draws' online trajectories cannot be fused (" << why
              << "): trajectory_online.txt is draw " << runs.seed(r.reference) << "'s\n";
  }
  return r;
}

// --draws, per frame of report.json: "ms".all_draws, the wall time of every draw (the frame's
// "ms" are the reference draw's own stages, beside the shared detection), and "draws_spread",
// the RMS distance of the fused draws' positions from their mean (the reference's unit; null:
// no fused pose).
void AddDrawsToFrames(const SystemEnsemble& runs, const DrawsResult& draws,
                      const std::vector<FrameStats>& stats, nlohmann::json* frames) {
  std::map<int64_t, double> spread_at;
  if (draws.fused_several()) {
    for (size_t i = 0; i < draws.fused.trajectory.size(); ++i) {
      spread_at[draws.fused.trajectory.poses[i].t_ns] = draws.fused.spread[i];
    }
  }
  size_t tracked = 0;  // SystemEnsemble::wall_ms has one entry per frame tracked (not skipped).
  for (size_t i = 0; i < stats.size(); ++i) {
    nlohmann::json& frame = (*frames)[i];
    if (!stats[i].skipped && tracked < runs.wall_ms().size()) {
      frame["ms"]["all_draws"] = runs.wall_ms()[tracked++];
    }
    const auto spread = spread_at.find(stats[i].t_ns);
    frame["draws_spread"] =
        spread == spread_at.end() ? nlohmann::json(nullptr) : nlohmann::json(spread->second);
  }
}

// summary.draws: each draw's seed, poses, ATE (with ground truth) and scale onto the fused
// trajectory, and the draws' spread around it.
nlohmann::json DrawsJson(const SystemEnsemble& runs, const std::vector<Trajectory>& final_runs,
                         const DrawsResult& draws, const Dataset& dataset,
                         const SystemOptions& options, int threads) {
  nlohmann::json per_draw = nlohmann::json::array();
  const auto& gt = dataset.ground_truth();
  EvalOptions eval;
  eval.alignment = EvaluationAlignment(options);
  for (int k = 0; k < runs.size(); ++k) {
    nlohmann::json d = {{"seed", runs.seed(k)}, {"frames_with_pose", final_runs[k].size()}};
    std::optional<double> ate;
    if (gt && !gt->empty() && !final_runs[k].empty()) {
      const EvalResult result = Evaluate(*gt, final_runs[k], eval);
      if (result.ok) ate = result.ate.translation.rmse;
    }
    d["ate_rmse"] = JsonOrNull(ate);
    const auto fused_at = std::find(draws.fused_draws.begin(), draws.fused_draws.end(), k) -
                          draws.fused_draws.begin();
    const bool in_fusion =
        draws.fused_several() && fused_at < static_cast<long>(draws.fused_draws.size());
    d["in_fusion"] = in_fusion;
    d["scale_onto_fused"] = JsonOrNull(
        in_fusion ? std::optional<double>(draws.fused.alignments[fused_at].scale) : std::nullopt);
    per_draw.push_back(d);
  }
  // The spread where two draws or more have the frame (one alone has none).
  std::vector<double> spread_values;
  if (draws.fused_several()) {
    for (size_t i = 0; i < draws.fused.spread.size(); ++i) {
      if (draws.fused.runs[i] > 1) spread_values.push_back(draws.fused.spread[i]);
    }
  }
  const ErrorStatistics spread = ComputeStatistics(spread_values);
  const bool with_spread = !spread_values.empty();
  return {
      {"count", runs.size()},
      {"threads", threads},
      {"reference_seed", runs.seed(draws.reference)},
      {"fused", draws.fused_several() ? static_cast<int>(draws.fused_draws.size()) : 0},
      {"alignment", AlignmentTypeName(runs.FusionAlignment())},
      {"not_fused",
       draws.not_fused.empty() ? nlohmann::json(nullptr) : nlohmann::json(draws.not_fused)},
      // RMS distance of the fused draws' aligned positions from their mean, over the frames
      // two draws or more have (the reference's unit).
      {"spread_median",
       JsonOrNull(with_spread ? std::optional<double>(spread.median) : std::nullopt)},
      {"spread_max", JsonOrNull(with_spread ? std::optional<double>(spread.max) : std::nullopt)},
      {"per_draw", per_draw}};
}

// Writing the outputs: each file is written to a temporary and renamed, so none is ever half
// written.
struct FrameCounts {
  std::vector<double> total_ms;
  // Lost: frames the estimator could not estimate (extrapolated) and skipped frames (unreadable
  // images: no pose); initialising: frames a mono estimator saw before its map existed. The
  // trajectory leaves out the frames without a pose.
  int failures = 0, skipped = 0, initialising = 0, keyframes = 0, loops = 0, loops_closed = 0;
  int keyframes_in_map = -1;  // The estimator's map after the last frame (-1: it keeps none).
  std::vector<double> loop_ms;  // Place recognition, per keyframe.
};

FrameCounts CountFrames(const std::vector<FrameStats>& stats) {
  FrameCounts c;
  for (const FrameStats& s : stats) {
    if (!s.skipped) c.total_ms.push_back(s.total_ms);
    c.loops += s.loop;
    c.loops_closed += s.loop_closed;
    if (s.keyframe) c.loop_ms.push_back(s.frontend.loop_ms);
    c.initialising += s.status == TrackingStatus::kInitializing && !s.valid;
    c.failures += !s.valid && s.status != TrackingStatus::kInitializing;
    c.skipped += s.skipped;
    c.keyframes += s.keyframe;
    if (s.keyframes_in_map >= 0) c.keyframes_in_map = s.keyframes_in_map;
  }
  return c;
}

nlohmann::json Summary(const System& system, const FrameCounts& c, const FramesRun& run,
                       const RefinementSummary& refinement, size_t frames_with_pose,
                       size_t landmarks) {
  const std::vector<double>& total_ms = c.total_ms;
  const size_t frames = system.stats().size();
  return {
      {"frames", frames},
      {"fps", frames / std::max(run.wall_s, 1e-9)},
      {"ms_mean", total_ms.empty()
                      ? 0.0
                      : std::accumulate(total_ms.begin(), total_ms.end(), 0.0) / total_ms.size()},
      {"ms_median", Percentile(total_ms, 0.5)},
      {"ms_p95", Percentile(total_ms, 0.95)},
      {"ms_max", total_ms.empty() ? 0.0 : *std::max_element(total_ms.begin(), total_ms.end())},
      {"stages_ms", StageTable(system.stats())},
      {"tracking_failures", c.failures},  // Including the skipped frames.
      {"frames_skipped", c.skipped},      // Unreadable images: no pose (note "skipped: ...").
      // Stopped by SIGINT / SIGTERM before the end (the outputs cover the frames done) or
      // during the global BA after it (refinement.report says "stopped on request").
      {"interrupted", run.signal != 0},
      {"frames_initialising", c.initialising},
      {"frames_with_pose", frames_with_pose},
      // "scale" is the evaluation's Sim(3) scale (below): what fixes the map's unit is this.
      {"scale_source", system.ScaleDescription()},
      // The stereo rig's disparity offset at the end and where it comes from (Estimator::
      // DisparityOffsetNote; empty: none).
      {"disparity_offset", system.estimator().DisparityOffsetNote()},
      // Its value in pixels (null: the estimator has none).
      {"disparity_offset_px", JsonOrNull(system.estimator().DisparityOffsetPx())},
      {"keyframes", c.keyframes},
      // Keyframes left in the estimator's map (made minus culled; -1: the estimator keeps none).
      {"keyframes_in_map", c.keyframes_in_map},
      // Keyframes with an entry in the place recognition (one per place on revisits).
      {"places", system.places()},
      {"loops_detected", c.loops},
      {"loops_closed", c.loops_closed},
      {"loop_ms_per_keyframe",
       {{"median", Percentile(c.loop_ms, 0.5)},
        {"p95", Percentile(c.loop_ms, 0.95)},
        {"max", c.loop_ms.empty() ? 0.0 : *std::max_element(c.loop_ms.begin(), c.loop_ms.end())}}},
      {"landmarks", landmarks},
      // The global BA after the last frame (ba.final_ba): trajectory.txt is its result,
      // trajectory_online.txt the trajectory before it (as each frame was estimated, with the
      // window's later corrections); "online" below evaluates that one.
      {"refinement",
       {{"done", refinement.done},
        {"report", refinement.report},
        {"keyframes", refinement.keyframes},
        {"landmarks", refinement.landmarks},
        {"observations", refinement.observations},
        {"outliers_removed", refinement.outliers_removed},
        {"initial_cost", refinement.initial_cost},
        {"final_cost", refinement.final_cost},
        {"time_s", refinement.time_s}}}};
}

// Memory against frames: keyframes so far, kept in the map, places stored, and resident memory
// (bounded by the place, not the time, is what this curve shows or not).
void DrawMemoryChart(const std::vector<FrameStats>& stats, const std::vector<double>& rss_mb,
                     const std::string& png_path) {
  bench::ChartSeries keyframe_curve{"keyframes made", {}, {}};
  // Culling (docs/backend.md): what the map keeps of them.
  bench::ChartSeries map_curve{"keyframes in the map", {}, {}};
  // One entry per place (docs/backend.md): what the memory follows on revisits.
  bench::ChartSeries place_curve{"places stored", {}, {}};
  bench::ChartSeries rss_curve{"resident memory", {}, {}};
  int keyframes_so_far = 0;
  int places_so_far = 0;
  int in_map_so_far = 0;
  for (size_t i = 0; i < stats.size(); ++i) {
    keyframes_so_far += stats[i].keyframe;
    if (!stats[i].skipped) places_so_far = stats[i].places;
    if (!stats[i].skipped) in_map_so_far = stats[i].keyframes_in_map;
    keyframe_curve.x.push_back(static_cast<double>(i));
    keyframe_curve.y.push_back(keyframes_so_far);
    if (in_map_so_far >= 0) {
      map_curve.x.push_back(static_cast<double>(i));
      map_curve.y.push_back(in_map_so_far);
    }
    place_curve.x.push_back(static_cast<double>(i));
    place_curve.y.push_back(places_so_far);
    if (i < rss_mb.size()) {
      rss_curve.x.push_back(static_cast<double>(i));
      rss_curve.y.push_back(rss_mb[i]);
    }
  }
  bench::LineChartOptions top, bottom;
  top.title = "keyframes made, kept in the map, and stored places";
  top.x_label = "frame";
  top.y_label = "count";
  bottom.title = "resident memory of the process";
  bottom.x_label = "frame";
  bottom.y_label = "MiB";
  std::vector<bench::ChartSeries> counts = {keyframe_curve, place_curve};
  if (!map_curve.x.empty()) counts.insert(counts.begin() + 1, map_curve);
  bench::DrawStackedLineCharts({{counts, top}, {{rss_curve}, bottom}}, png_path);
}

// Where the chosen estimator is known not to hold, said before any number (docs/ekf.md, "One
// camera: measured"): the mono EKF from one camera, with no odometry, has only a
// constant-velocity model to carry its scale and no loop closing to correct it.
std::string EstimatorLimitNote(const System& system, const SystemOptions& options) {
  if (options.estimator != "ekf" || options.mode != "mono") return "";
  if (system.ScaleDescription() != "arbitrary (monocular)") return "";
  return "the mono EKF from one camera (no odometry) drifts in scale and depends on the start "
         "frame (docs/ekf.md, \"One camera: measured\"); for one camera use --estimator ba, for "
         "this filter give it odometry (odometry.txt)";
}

// The loops the estimator judged and did not close, and the first one's reason.
std::string LoopsNotClosedNote(const System& system) {
  int count = 0;
  const FrameStats* first = nullptr;
  for (const FrameStats& s : system.stats()) {
    if (s.loop_not_closed.empty()) continue;
    ++count;
    if (!first) first = &s;
  }
  if (count == 0) return "";
  std::ostringstream os;
  os << count << " not closed; the first, at frame " << first->frame.value << " to frame "
     << (first->loop_old_frame ? std::to_string(first->loop_old_frame->value) : "?") << ": "
     << first->loop_not_closed
     << (count > 1 ? " (every one: loop_not_closed in report.json's frames)" : "");
  return os.str();
}

// --draws: what was fused, the draws' spread and each one's ATE.
void PrintDraws(const nlohmann::json& draws, std::ostream& out) {
  const nlohmann::json& per_draw = draws["per_draw"];
  const int fused = draws["fused"].get<int>();
  const std::string reference = "seed " + std::to_string(draws["reference_seed"].get<uint64_t>());
  std::ostringstream line;  // Its own number format, not the caller's.
  line << "draws       " << per_draw.size() << " runs (ransac_order_seed "
       << per_draw.front()["seed"].get<uint64_t>() << "-" << per_draw.back()["seed"].get<uint64_t>()
       << "); ";
  if (fused > 1) {
    line << fused << " fused by " << draws["alignment"].get<std::string>() << " into the world of "
         << reference << ": spread " << std::setprecision(3) << draws["spread_median"].get<double>()
         << " median, " << draws["spread_max"].get<double>()
         << " max (RMS distance of the draws from their mean, "
         << "in its unit)\n";
  } else if (!draws["not_fused"].is_null()) {
    line << "not fused: " << draws["not_fused"].get<std::string>() << "; the trajectory is "
         << reference << "'s\n";
  } else {
    line << "not fused: fewer than two draws have a trajectory; the trajectory is " << reference
         << "'s\n";
  }
  bool any_ate = false;
  for (const auto& d : per_draw) any_ate = any_ate || !d["ate_rmse"].is_null();
  if (any_ate) {
    line << "            ATE per draw" << std::fixed << std::setprecision(4);
    for (const auto& d : per_draw) {
      if (d["ate_rmse"].is_null()) {
        line << " -";
      } else {
        line << " " << d["ate_rmse"].get<double>();
      }
    }
    line << " m (each alone; draws/seed_K.txt)\n";
  }
  out << line.str();
}

// The summary `dala run` prints (and report.html shows).
void PrintSummary(const System& system, const FrameCounts& c, const nlohmann::json& summary,
                  const RefinementSummary& refinement, size_t frames_with_pose,
                  int64_t localised_at, const std::string& evaluation_error, bool plotted,
                  const std::string& dir, const SystemOptions& options, std::ostream& out) {
  const size_t frames = system.stats().size();
  const int keyframes = c.keyframes;
  out << "frames      " << frames << " (" << c.failures << " lost"
      << (c.skipped > 0 ? " of which " + std::to_string(c.skipped) + " skipped" : "") << ", "
      << c.initialising << " initialising, " << frames_with_pose << " with a pose, " << keyframes
      << " keyframes, " << c.loops << " loops detected, " << c.loops_closed << " closed)\n"
      << "scale       " << system.ScaleDescription() << "\n";
  if (const std::string note = LoopsNotClosedNote(system); !note.empty()) {
    out << "loops       " << note << "\n";
  }
  if (const std::string note = system.estimator().DisparityOffsetNote(); !note.empty()) {
    out << "disparity   offset " << note << "\n";
  }
  if (const std::string note = EstimatorLimitNote(system, options); !note.empty()) {
    out << "note        " << note << "\n";
  }
  if (refinement.stopped) {
    out << "note        the global BA after the last frame was stopped (Ctrl-C or SIGTERM): "
           "these are the results of --set ba.final_ba=off\n";
  }
  if (!FLAGS_map.empty()) {
    out << "saved map   " << FLAGS_map << ": "
        << (localised_at >= 0 ? "localised at frame " + std::to_string(localised_at)
                              : std::string("never localised (no frame recognised a "
                                            "mapped place; no frame has a pose)"))
        << "\n";
  }
  out << "memory      " << std::fixed << std::setprecision(0)
      << summary["peak_rss_mb"].get<double>() << " MiB peak resident, " << keyframes
      << " keyframes made"
      << (c.keyframes_in_map >= 0 ? ", " + std::to_string(c.keyframes_in_map) + " in the map"
                                  : std::string())
      << ", " << system.places() << " places stored (memory.png)\n";
  const nlohmann::json* draws = summary.contains("draws") ? &summary["draws"] : nullptr;
  out << "time        " << std::fixed << std::setprecision(1) << Percentile(c.total_ms, 0.5)
      << " ms median per frame, " << summary["fps"].get<double>() << " fps";
  if (draws != nullptr) {
    out << " (" << (*draws)["count"].get<int>() << " draws on " << (*draws)["threads"].get<int>()
        << ((*draws)["threads"].get<int>() > 1 ? " threads)" : " thread)");
  }
  out << "\n";
  if (draws != nullptr) PrintDraws(*draws, out);
  if (summary.contains("ate")) {
    out << "ATE rmse    " << std::setprecision(4) << summary["ate"]["rmse"].get<double>() << " m ("
        << AlignmentTypeName(EvaluationAlignment(options)) << " alignment"
        << (refinement.done ? ", after the global BA" : "")
        << (draws != nullptr && (*draws)["fused"].get<int>() > 1
                ? ", the " + std::to_string((*draws)["fused"].get<int>()) + " draws fused"
                : std::string())
        << ")\n";
    if (summary.contains("online") && summary["online"].contains("ate")) {
      out << "ATE online  " << std::setprecision(4)
          << summary["online"]["ate"]["rmse"].get<double>()
          << " m (before the global BA: trajectory_online.txt)\n";
    }
    if (summary.contains("scale_along_path") &&
        !summary["scale_along_path"]["segments"].empty()) {
      const nlohmann::json& sc = summary["scale_along_path"];
      out << "scale along " << std::setprecision(3) << sc["min"].get<double>() << " to "
          << sc["max"].get<double>() << " over " << sc["segments"].size() << " segments of "
          << std::setprecision(1) << sc["segment_m"].get<double>()
          << " m (the estimate's size against the truth's, after the alignment)\n";
    }
    for (const auto& w : summary["warnings"]) out << "note        " << w.get<std::string>() << "\n";
  }
  if (!evaluation_error.empty()) out << "evaluation  not done: " << evaluation_error << "\n";
  if (frames_with_pose < frames) {
    out << "note        " << frames - frames_with_pose
        << " frames have no pose (skipped, or before the monocular initialisation): "
           "trajectory files leave them out; pair trajectory_kitti.txt with ground truth "
           "by time (trajectory.txt)\n";
  }
  out << "results in  " << dir << "/ (trajectory.txt, trajectory_kitti.txt, map.ply, "
      << "map.dmap, report.json, report.html, memory.png" << (plotted ? ", trajectory.png" : "")
      << (refinement.done ? ", trajectory_online.txt" : "")
      << (draws != nullptr ? ", draws/seed_K.txt" : "") << ")\n";
}

// trajectory.txt (TUM), trajectory_online.txt (before the refinement, when there was one),
// trajectory_kitti.txt, map.ply and map.dmap; returns the map's points (report.html shows them).
std::vector<Eigen::Vector3d> WriteTrajectoryAndMap(const System& system,
                                                   const Trajectory& trajectory,
                                                   const Trajectory& online_trajectory,
                                                   bool refined, const std::string& dir) {
  WriteTrajectoryTum(dir + "/trajectory.txt", trajectory);
  if (refined) WriteTrajectoryTum(dir + "/trajectory_online.txt", online_trajectory);
  WriteTrajectoryKitti(dir + "/trajectory_kitti.txt", trajectory);
  std::vector<Eigen::Vector3d> points;
  std::vector<int64_t> ids;
  for (const MapPoint& p : system.map()) {
    points.push_back(p.p_w);
    ids.push_back(p.id.value);
  }
  WritePly(dir + "/map.ply", points, nullptr, &ids);
  system.SaveMap(dir + "/map.dmap");
  return points;
}

// The evaluation against the dataset's ground truth, when it has one, into the summary (SE(3)
// alignment, Sim(3) for one camera), and trajectory.png.
struct RunEvaluation {
  bool plotted = false;
  std::string error;  // Why the evaluation could not be done (empty: done, or no ground truth).
  std::optional<EvalResult> result;  // The evaluation (report.html); none without ground truth.
};

RunEvaluation EvaluateRun(const Dataset& dataset, const Trajectory& trajectory,
                          const Trajectory& online_trajectory, bool refined,
                          const SystemOptions& options, const std::string& dir,
                          nlohmann::json* summary) {
  RunEvaluation out;
  const auto& gt = dataset.ground_truth();
  if (!gt || gt->empty()) return out;
  EvalOptions eval;
  eval.alignment = EvaluationAlignment(options);
  out.result = Evaluate(*gt, trajectory, eval);
  const EvalResult& result = *out.result;
  const nlohmann::json e = EvalResultToJson(result);
  for (const auto& [key, value] : e.items()) (*summary)[key] = value;
  if (result.ok) (*summary)["scale_along_path"] = ScaleAlongPathToJson(MeasureScaleAlongPath(result));
  if (refined) {
    // The same evaluation of the trajectory as it was before the refinement.
    (*summary)["online"] = EvalResultToJson(Evaluate(*gt, online_trajectory, eval));
  }
  if (result.ok) {
    PlotEvaluation(*gt, AlignTrajectory(trajectory, result.alignment), result,
                   dir + "/trajectory.png");
    out.plotted = true;
  } else {
    out.error = result.error;
  }
  return out;
}

// report.html (tools/report): the run's map, keyframes, path and ground truth in 3D, its
// per-frame charts and the printed summary, from the results just written (never the
// estimator's state). Returns the time it took, in milliseconds.
double WriteReport(const Dataset& dataset, const Trajectory& trajectory,
                   const std::optional<EvalResult>& evaluation,
                   std::vector<Eigen::Vector3d> map_points, const nlohmann::json& report,
                   const std::string& dir) {
  const auto start = std::chrono::steady_clock::now();
  report::ReportInput input;
  input.title = report["dataset"]["path"].get<std::string>();
  input.trajectory = trajectory;
  if (evaluation && dataset.ground_truth()) {
    input.ground_truth = dataset.ground_truth();
    input.evaluation = evaluation;
  }
  input.points_w = std::move(map_points);
  input.keyframes = report::KeyframesFromFrames(report["frames"], trajectory);
  input.frames = report["frames"];
  input.summary = report["summary"];
  input.summary_text = report["summary_text"].get<std::string>();
  const PinholeCamera& camera = dataset.rig().left;
  if (camera.width > 0 && camera.height > 0) {
    input.image_aspect = static_cast<double>(camera.width) / camera.height;
  }
  report::WriteReportHtml(dir + "/report.html", report::ReportDataJson(input));
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

int RunRun(const std::vector<std::string>& args) {
  const SystemOptions options = OptionsFromFlags();
  if (FLAGS_dump_config || FLAGS_dump_config_all) {
    std::cout << SystemOptionsToYaml(options,
                                     FLAGS_dump_config_all ? OptionSet::kAll : OptionSet::kUser);
    return 0;
  }
  if (args.size() != 1) {
    throw Error() << "expected one dataset folder, got " << args.size()
                  << " arguments; usage: dala run DATASET --out DIR";
  }
  if (FLAGS_out.empty()) throw Error() << "--out DIR is required (where the results go)";
  if (FLAGS_draws < 1) {
    throw Error() << "--draws " << FLAGS_draws << ": give 1 (one run, the default) or more";
  }
  if (FLAGS_threads < 0)
    throw Error() << "--threads " << FLAGS_threads << ": give 0 (one per core) or more";
  std::unique_ptr<Dataset> dataset = OpenDataset(args[0], DatasetOptionsFromFlags(options));
  CreateDirectories(FLAGS_out);
  PrepareDrawsFolder(FLAGS_out, FLAGS_draws);

  SystemEnsembleOptions ensemble_options;
  ensemble_options.draws = FLAGS_draws;
  ensemble_options.threads = std::min(
      FLAGS_draws, FLAGS_threads > 0
                       ? FLAGS_threads
                       : std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  SystemEnsemble runs(dataset->rig(), options, ensemble_options);
  if (!FLAGS_map.empty()) {
    const SavedMap saved = System::LoadMap(FLAGS_map);
    runs.UseMap(saved);
    std::cerr << "[run] starting in the saved map " << FLAGS_map << " ("
              << saved.keyframes.size() << " keyframes, " << saved.landmarks.size()
              << " landmarks, " << (saved.metric ? "metric" : "arbitrary unit")
              << "): frames without a pose until one is relocalised in it\n";
  }
  // Ctrl-C / SIGTERM from here on: stop after the current frame and write the results so far.
  // (Installed before the line below, which tells a watching process that the run started.)
  const StopSignal stop;
  std::cerr << "[run] " << args[0] << " (" << DatasetFormatName(dataset->format()) << ", "
            << dataset->size() << " frames, " << (dataset->is_stereo() ? "stereo" : "mono")
            << ") with " << options.estimator << "/" << options.mode;
  if (runs.size() > 1) {
    std::cerr << ", " << runs.size() << " draws (ransac_order_seed " << runs.seed(0) << "-"
              << runs.seed(runs.size() - 1) << ") on " << ensemble_options.threads << " thread"
              << (ensemble_options.threads > 1 ? "s" : "");
  }
  std::cerr << "\n";
  // --video: what the frontend saw, frame by frame.
  std::optional<report::FrameVideo> video;
  if (!FLAGS_video.empty()) video.emplace(FLAGS_video);
  FramesRun run = TrackEveryFrame(dataset.get(), &runs, stop, video ? &*video : nullptr);
  // The causal (online) trajectories, then the global refinement of the whole run.
  const std::vector<Trajectory> online_runs = runs.Trajectories();
  const std::vector<RefinementSummary> refinements = Refine(&runs, &run, options, stop);
  const std::vector<Trajectory> final_runs = runs.Trajectories();
  const DrawsResult draws =
      FuseDraws(runs, final_runs, online_runs,
                std::any_of(refinements.begin(), refinements.end(),
                            [](const RefinementSummary& r) { return r.done; }));
  // The draw whose map, report and per-frame statistics are written (the only one by default).
  const System& system = runs.draw(draws.reference);
  const RefinementSummary& refinement = refinements[draws.reference];

  // Outputs: each file is written to a temporary and renamed, so none is ever half written.
  const std::string dir = FLAGS_out;
  const Trajectory& trajectory = draws.trajectory;
  std::vector<Eigen::Vector3d> map_points =
      WriteTrajectoryAndMap(system, trajectory, draws.online_trajectory, refinement.done, dir);
  const size_t landmarks = map_points.size();
  if (runs.size() > 1) {
    for (int k = 0; k < runs.size(); ++k) {
      WriteTrajectoryTum(dir + "/draws/seed_" + std::to_string(runs.seed(k)) + ".txt",
                         final_runs[k]);
    }
  }

  const auto& stats = system.stats();
  FrameCounts counts = CountFrames(stats);
  // Several draws: a frame's time is the wall time of all of them.
  if (runs.size() > 1) counts.total_ms = runs.wall_ms();
  nlohmann::json summary =
      Summary(system, counts, run, refinement, trajectory.size(), landmarks);
  if (runs.size() > 1) {
    summary["draws"] =
        DrawsJson(runs, final_runs, draws, *dataset, options, ensemble_options.threads);
  }
  // --map: the first frame placed in the saved map (-1: none).
  int64_t localised_at = -1;
  if (!FLAGS_map.empty()) {
    for (const FrameStats& s : stats) {
      if (s.valid) {
        localised_at = s.frame.value;
        break;
      }
    }
    summary["saved_map"] = {{"path", FLAGS_map}, {"localised_at_frame", localised_at}};
  }
  const RunEvaluation evaluation = EvaluateRun(*dataset, trajectory, draws.online_trajectory,
                                               refinement.done, options, dir, &summary);
  nlohmann::json frames = nlohmann::json::array();
  for (size_t i = 0; i < stats.size(); ++i) {
    frames.push_back(FrameJson(stats[i]));
    if (i < run.rss_mb.size()) frames.back()["rss_mb"] = run.rss_mb[i];
  }
  if (runs.size() > 1) AddDrawsToFrames(runs, draws, stats, &frames);
  summary["peak_rss_mb"] = PeakResidentMemoryMb();
  DrawMemoryChart(stats, run.rss_mb, dir + "/memory.png");
  std::ostringstream printed;
  PrintSummary(system, counts, summary, refinement, trajectory.size(), localised_at,
               evaluation.error, evaluation.plotted, dir, options, printed);
  const nlohmann::json report = {
      {"dataset",
       {{"path", args[0]},
        // The same, absolute: where `dala view` finds the ground truth from another folder.
        {"absolute_path", std::filesystem::absolute(args[0]).lexically_normal().string()},
        {"format", DatasetFormatName(dataset->format())},
        {"frames", dataset->size()},
        {"stereo", dataset->is_stereo()}}},
      {"estimator", options.estimator},
      {"mode", options.mode},
      {"options", SystemOptionsToJson(options)},
      {"frames", frames},
      {"summary", summary},
      // What `dala run` printed (report.html and `dala view` show it).
      {"summary_text", printed.str()}};
  WriteFileAtomically(dir + "/report.json", [&](std::ostream& os) { os << report.dump(1) << "\n"; });
  const double report_ms = WriteReport(*dataset, trajectory, evaluation.result,
                                       std::move(map_points), report, dir);

  std::cout << printed.str();
  if (video) {
    const int video_frames = video->frames();
    const double video_ms = video->ms_per_frame();
    const std::string video_path = video->Close();
    std::cout << "video       " << video_path << " (" << video_frames << " frames, "
              << std::fixed << std::setprecision(1) << video_ms << " ms per frame to draw and "
              << "encode)\n";
  }
  std::cout << "report      " << dir << "/report.html (3D view, charts; written in " << std::fixed
            << std::setprecision(0) << report_ms << " ms)\n";
  if (std::any_of(refinements.begin(), refinements.end(),
                  [](const RefinementSummary& r) { return r.stopped; })) {
    // With --draws N the draws are refined side by side: one whose BA had finished keeps it.
    const auto finished = std::count_if(refinements.begin(), refinements.end(),
                                        [](const RefinementSummary& r) { return r.done; });
    std::cerr << "[run] interrupted by " << StopSignalName(run.signal) << " during the global BA: "
              << "the results are those of ba.final_ba=off";
    if (finished > 0) {
      std::cerr << " but for the " << finished << " of " << refinements.size()
                << " draws whose global BA had finished";
    }
    std::cerr << " (report.json: summary.interrupted)\n";
    return 128 + run.signal;
  }
  if (run.signal != 0) {
    std::cerr << "[run] interrupted by " << StopSignalName(run.signal) << ": the results cover the "
              << run.done << " frames done of " << dataset->size() << " (report.json: "
              << "summary.interrupted)\n";
    return 128 + run.signal;  // As a shell reports a process ended by the signal (130 for SIGINT).
  }
  return 0;
}

const CommandRegistrar kRegistrar(
    {"run", "reconstruct the camera trajectory and a map from a dataset folder",
     "dala run DATASET --out DIR [--config FILE] [--estimator ba|ekf] [--mode stereo|mono]\n"
     "         [--set section.key=value ...] [--format auto|kitti|euroc|tum|synthetic]\n"
     "         [--first_frame N] [--max_frames N] [--calibration FILE] [--strict]\n"
     "         [--map FILE] [--video FILE.mp4] [--draws N [--threads T]]\n"
     "         [--dump_config | --dump_config_all]\n"
     "       dala run VIDEO|IMAGE_FOLDER --calibration FILE --out DIR [--mode mono]\n"
     "         [--fps HZ] [--times FILE] [--right_folder DIR] [--stereo_layout side_by_side]\n"
     "         [--ground_truth FILE]\n"
     "       dala run FILE.bag --topic /cam0/image_raw [--right_topic /cam1/image_raw]\n"
     "         [--calibration FILE] --out DIR (a ROS 1 bag; CameraInfo from the bag when "
     "present)\n\n"
     "Runs the visual frontend and the chosen estimator over every frame of DATASET (a KITTI\n"
     "odometry sequence, an EuRoC ASL folder, a TUM RGB-D folder, a `dala synth` output, a\n"
     "folder of images or a video file with its calibration: docs/datasets.md) and\n"
     "writes into DIR: trajectory.txt (TUM, every frame with a pose), trajectory_kitti.txt,\n"
     "map.ply, map.dmap (keyframes, landmarks, descriptors; docs/api.md), report.json (options,\n"
     "per-frame timings and counts, summary with ATE/RPE/KITTI errors when the dataset has\n"
     "ground truth), trajectory.png (estimate over ground truth), memory.png (keyframes\n"
     "and resident memory against frames; report.json has each frame's rss_mb) and\n"
     "report.html (the run in 3D with its charts and summary, one file that opens from disk;\n"
     "`dala view DIR` writes it again). --video FILE.mp4 also writes what the frontend saw.\n\n"
     "--set ba.final_ba=always (or after_loop: when the run closed a loop) refines the whole run\n"
     "after its last frame by a global bundle adjustment over every keyframe (BA estimator; by\n"
     "default only for a stereo rig whose disparity offset was calibrated, with the offset free:\n"
     "rig_offset; docs/backend.md): trajectory.txt is then the refined trajectory,\n"
     "trajectory_online.txt the one before (each frame as estimated while the run went on), and\n"
     "report.json evaluates both (summary.ate, summary.online.ate).\n\n"
     "A frame whose image is missing, unreadable or of the wrong size is skipped with a warning\n"
     "and reported lost, without a pose (--strict: exit 2 instead); the first frame must be\n"
     "readable. Ctrl-C (SIGINT) or SIGTERM stops after the current frame: the results of the\n"
     "frames done are written as usual, report.json says interrupted, exit status 128 + signal;\n"
     "during the global BA after the last frame it stops that, and the results are those of\n"
     "--set ba.final_ba=off.\n\n"
     "--map FILE starts in the map.dmap of an earlier run (same camera and options; a stereo run\n"
     "needs a stereo map): each frame is relocalised against the map's keyframes until one is\n"
     "placed (frames before have no pose), then the run continues in the map's frame and unit;\n"
     "report.json's summary.saved_map.localised_at_frame says where (ba estimator only).\n\n"
     "--draws N runs the pipeline N times over the same frames, stepped together on --threads\n"
     "threads, with the RANSAC draws ransac_order_seed + 0..N-1, and writes their per-frame mean\n"
     "(each draw aligned onto it by Sim(3) with one camera, SE(3) with a metric scale; `dala\n"
     "fuse`) as trajectory.txt, in the first draw's world and unit; map.ply, map.dmap and the\n"
     "per-frame report are the first draw's, draws/seed_K.txt each draw's trajectory, and\n"
     "report.json's summary.draws each draw's ATE and the draws' spread. It costs N runs' work;\n"
     "it pays where the draws disagree (one camera on real images: docs/evaluation.md,\n"
     "\"Several draws in one run\").",
     &RunRun, __FILE__});

}  // namespace
}  // namespace dala
