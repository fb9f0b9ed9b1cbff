#include "tools/bench/bench.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "tools/bench/evaluate_run.h"
#include "tools/bench/report_writer.h"
#include "tools/bench/run_result.h"
#include "tools/bench/subprocess.h"

namespace dala::bench {
namespace fs = std::filesystem;
namespace {

constexpr const char* kDoneMarker = "bench_done.json";
constexpr const char* kSeriesFile = "bench_series.json";
constexpr const char* kRenderedMarker = "bench_rendered.json";

// Calls fn(0..n-1) on `jobs` threads; each index once.
void ParallelFor(int n, int jobs, const std::function<void(int)>& fn) {
  std::atomic<int> next{0};
  const auto worker = [&] {
    for (int i = next++; i < n; i = next++) fn(i);
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < std::min(jobs, n); ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

// What determines a run's result: if it changes, a finished run is not reused.
nlohmann::json RunSpec(const BenchRun& run) {
  const SequenceSpec& s = run.sequence;
  const ConfigSpec& c = run.config;
  nlohmann::json sequence = s.is_rendered() ? nlohmann::json{{"preset", s.preset},
                                                             {"frames", s.frames},
                                                             {"seed", s.seed},
                                                             {"mono", s.mono}}
                                            : nlohmann::json{{"path", s.path}};
  // Only for start variants, so that the markers of runs without starts stay valid.
  if (run.has_start()) sequence["first_frame"] = run.first_frame;
  nlohmann::json spec = {{"sequence", sequence},
                         {"estimator", c.estimator},
                         {"mode", c.mode},
                         {"config", c.config_file},
                         {"set", c.set}};
  // Likewise only when given, for the markers of the runs without it.
  if (c.draws > 1) spec["draws"] = c.draws;
  return spec;
}

std::optional<nlohmann::json> ReadJsonFile(const std::string& path) {
  std::ifstream is(path);
  if (!is) return std::nullopt;
  try {
    return nlohmann::json::parse(is);
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

void WriteJsonFile(const std::string& path, const nlohmann::json& j) {
  WriteFileAtomically(path, [&](std::ostream& os) { os << j.dump(1) << "\n"; });
}

void CheckWritable(const std::string& dir) {
  try {
    CreateDirectories(dir);
  } catch (const Error& e) {
    throw Error() << "--out=" << dir << ": cannot create the output folder (" << e.what() << ")";
  }
  const std::string probe = dir + "/.bench_write_test." + std::to_string(::getpid());
  std::ofstream os(probe);
  const bool ok = static_cast<bool>(os << "x");
  os.close();
  std::error_code ec;
  fs::remove(probe, ec);
  if (!ok) throw Error() << "--out=" << dir << ": the output folder is not writable";
}

class ProgressPrinter {
 public:
  explicit ProgressPrinter(int total) : total_(total) {}
  void Print(const std::string& line) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    std::cerr << "[" << done_ << "/" << total_ << "] " << line << std::endl;
  }

 private:
  std::mutex mutex_;
  int total_;
  int done_ = 0;
};

std::string Seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f s", s);
  return buf;
}

struct SequenceState {
  std::string folder;  // Absolute.
  std::string render_error;
  std::optional<Trajectory> ground_truth;
  std::string gt_why;
};

// Renders a preset into DIR/sequences/NAME with `dala synth` unless it is already there (same
// preset, frames, seed, mono). Renders into a temporary folder first, so that an interrupted
// render is never mistaken for a finished one.
std::string RenderSequence(const SequenceSpec& s, const BenchOptions& options,
                           const std::string& folder) {
  const nlohmann::json spec = {
      {"preset", s.preset}, {"frames", s.frames}, {"seed", s.seed}, {"mono", s.mono}};
  const auto marker = ReadJsonFile(folder + "/" + kRenderedMarker);
  if (marker && *marker == spec) return "";
  const std::string tmp = folder + ".tmp";
  std::error_code ec;
  fs::remove_all(tmp, ec);
  CreateDirectories(fs::path(folder).parent_path().string());
  std::vector<std::string> argv = {options.dala_path, "synth", "--preset", s.preset,
                                   "--out",           tmp,     "--seed",   std::to_string(s.seed)};
  if (s.frames > 0) argv.insert(argv.end(), {"--frames", std::to_string(s.frames)});
  if (s.mono) argv.push_back("--mono");
  SubprocessOptions sub;
  sub.log_path = folder + ".synth.log";
  const SubprocessResult r = RunSubprocess(argv, sub);
  if (!r.started) return "dala synth could not start: " + r.error;
  if (!r.exited || r.exit_code != 0) {
    const std::string tail = TailOfFile(sub.log_path);
    return "dala synth failed (" +
           (r.exited ? "exit status " + std::to_string(r.exit_code)
                     : "signal " + std::to_string(r.signal)) +
           ")" + (tail.empty() ? "" : ": " + tail) + " [" + ShellJoin(argv) + "]";
  }
  WriteJsonFile(tmp + "/" + kRenderedMarker, spec);
  fs::remove_all(folder, ec);
  fs::rename(tmp, folder, ec);
  if (ec) return "cannot move " + tmp + " to " + folder + ": " + ec.message();
  fs::remove(sub.log_path, ec);
  return "";
}

std::vector<std::string> RunCommand(const BenchRun& run, const std::string& dala,
                                    const std::string& sequence_folder,
                                    const std::string& run_dir) {
  std::vector<std::string> argv = {dala,           "run",         sequence_folder,      "--out",
                                   run_dir,        "--estimator", run.config.estimator, "--mode",
                                   run.config.mode};
  if (!run.config.config_file.empty()) {
    argv.insert(argv.end(), {"--config", run.config.config_file});
  }
  for (const std::string& kv : run.config.set) argv.insert(argv.end(), {"--set", kv});
  if (run.config.draws > 1) argv.insert(argv.end(), {"--draws", std::to_string(run.config.draws)});
  if (run.has_start()) argv.insert(argv.end(), {"--first_frame", std::to_string(run.first_frame)});
  return argv;
}

// Where a run's outputs go, relative to the output folder: runs/SEQ[@VARIANT]/CONFIG.
std::string RunDirOf(const BenchRun& run) { return "runs/" + run.key(); }

// The folder a run reads: DIR/sequences/SEQ[@seedS] for a rendered preset, else the dataset.
std::string SequenceFolderOf(const BenchRun& run, const std::string& out_dir) {
  return run.sequence.is_rendered() ? out_dir + "/sequences/" + run.folder_name()
                                    : run.sequence.path;
}

// Resume: a run whose folder holds its report.json and a done marker for the same specification
// is not rerun; its recorded row is reused.
bool ReuseDoneRun(const BenchRun& run, const std::string& out_dir, BenchRunResult* row) {
  const std::string run_dir = out_dir + "/" + RunDirOf(run);
  if (!fs::is_regular_file(run_dir + "/report.json")) return false;
  const auto done = ReadJsonFile(run_dir + "/" + kDoneMarker);
  if (!done || !done->contains("spec") || done->at("spec") != RunSpec(run) ||
      !done->contains("result")) {
    return false;
  }
  try {
    *row = BenchRunResultFromJson(done->at("result"), run_dir + "/" + kDoneMarker);
  } catch (const Error&) {
    return false;  // A damaged marker: rerun.
  }
  row->index = run.index;
  return true;
}

// Runs `dala run` in a fresh run folder, evaluates it and writes the done marker.
void ExecuteRun(const BenchRun& run, const SequenceState& seq, const BenchOptions& options,
                double timeout_s, BenchRunResult* r) {
  const std::string run_dir = options.out_dir + "/" + RunDirOf(run);
  const std::vector<std::string> argv = RunCommand(run, options.dala_path, seq.folder, run_dir);
  r->index = run.index;
  r->sequence = run.sequence.name;
  r->config = run.config.name;
  r->variant = run.variant;
  if (run.sequence.is_rendered()) {
    r->seed = run.sequence.seed;
  } else {
    r->start = run.first_frame;
  }
  r->estimator = run.config.estimator;
  r->mode = run.config.mode;
  r->run_dir = RunDirOf(run);
  r->command = ShellJoin(argv);
  try {
    std::error_code ec;
    fs::remove_all(run_dir, ec);  // No stale outputs of an earlier attempt.
    CreateDirectories(run_dir);
    if (!seq.render_error.empty()) {
      r->status = kStatusFailed;
      r->error = "sequence not available: " + seq.render_error;
    } else {
      SubprocessOptions sub;
      sub.log_path = run_dir + "/log.txt";
      sub.timeout_s = timeout_s;
      const SubprocessResult child = RunSubprocess(argv, sub);
      RunSeries series;
      EvaluateRun(run, child, run_dir, seq.ground_truth, seq.gt_why, r, &series);
      WriteJsonFile(run_dir + "/" + kSeriesFile, ToJson(series));
    }
    // The done marker last: it is what resume trusts.
    WriteJsonFile(run_dir + "/" + kDoneMarker, {{"spec", RunSpec(run)}, {"result", ToJson(*r)}});
  } catch (const Error& e) {
    r->status = kStatusFailed;
    r->error += (r->error.empty() ? "" : "; ") + std::string(e.what());
  }
}

std::string Describe(const BenchRunResult& r) {
  std::string line = RunKey(r) + "  " + r.status + "  " + Seconds(r.wall_s);
  if (r.ate_rmse) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "  ATE %.4f m", *r.ate_rmse);
    line += buf;
  }
  if (r.status != kStatusOk && !r.error.empty()) {
    std::string first = r.error.substr(r.error.find_last_of('\n') + 1);  // The last line.
    if (first.size() > 160) first = first.substr(0, 160) + "...";
    line += "  (" + first + ")";
  }
  return line;
}

void WriteAll(const std::string& out_dir, const BenchHeader& header,
              std::vector<BenchRunResult> rows) {
  std::sort(rows.begin(), rows.end(), [](const BenchRunResult& a, const BenchRunResult& b) {
    return std::tie(a.index, a.sequence, a.config) < std::tie(b.index, b.sequence, b.config);
  });
  std::map<std::string, RunSeries> series;
  for (const BenchRunResult& r : rows) {
    if (const auto j = ReadJsonFile(out_dir + "/" + r.run_dir + "/" + kSeriesFile)) {
      series[r.run_dir] = RunSeriesFromJson(*j);
    }
  }
  WriteBenchOutputs(out_dir, header, rows, series);
}

}  // namespace

bool BenchOptions::IsValid(std::string* why) const {
  if (out_dir.empty()) {
    *why = "--out is required (the output folder)";
    return false;
  }
  if (jobs < 1) {
    *why = "--jobs must be >= 1";
    return false;
  }
  if (dala_path.empty() || access(dala_path.c_str(), X_OK) != 0) {
    *why = "--dala=" + dala_path + ": not an executable file";
    return false;
  }
  return true;
}

BenchSummary RunBench(const BenchSuite& suite, const BenchOptions& options_in) {
  std::string why;
  if (!options_in.IsValid(&why)) throw Error() << why;
  BenchOptions options = options_in;
  options.out_dir = fs::absolute(options.out_dir).lexically_normal().string();
  options.dala_path = fs::absolute(options.dala_path).string();
  if (!options.out_dir.empty() && options.out_dir.back() == '/') options.out_dir.pop_back();
  CheckWritable(options.out_dir);
  const double timeout_s = options.timeout_s >= 0 ? options.timeout_s : suite.timeout_s;

  const std::vector<BenchRun> all = MakeRunList(suite);
  const std::vector<BenchRun> runs = SelectShard(all, options.shard);
  std::cerr << "dala bench: " << runs.size() << " runs (shard " << options.shard.ToString()
            << " of " << all.size() << "), " << options.jobs << " at once, into " << options.out_dir
            << std::endl;

  // Sequence folders of this shard (one per seed of a rendered preset; the start variants of a
  // dataset share its folder): render the presets, load the ground truth.
  std::map<std::string, SequenceState> sequences;  // By folder.
  std::vector<const BenchRun*> to_render;
  for (const BenchRun& run : runs) {
    const std::string folder = SequenceFolderOf(run, options.out_dir);
    if (sequences.count(folder)) continue;
    sequences[folder].folder = folder;
    if (run.sequence.is_rendered()) to_render.push_back(&run);
  }
  ParallelFor(static_cast<int>(to_render.size()), options.jobs, [&](int i) {
    const BenchRun& run = *to_render[i];
    const std::string folder = SequenceFolderOf(run, options.out_dir);
    const auto start = std::chrono::steady_clock::now();
    std::string error;
    try {
      error = RenderSequence(run.sequence, options, folder);
    } catch (const Error& e) {
      error = e.what();
    }
    sequences.at(folder).render_error = error;  // Distinct map entries: no data race.
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cerr << "sequence " << run.folder_name() << ": "
              << (error.empty() ? "ready (" + Seconds(secs) + ")" : "FAILED: " + error)
              << std::endl;
  });
  for (auto& [name, state] : sequences) {
    if (state.render_error.empty())
      state.ground_truth = LoadGroundTruth(state.folder, &state.gt_why);
  }

  std::vector<BenchRunResult> rows(runs.size());
  std::vector<char> skipped(runs.size(), 0);
  ProgressPrinter progress(static_cast<int>(runs.size()));
  ParallelFor(static_cast<int>(runs.size()), options.jobs, [&](int k) {
    const SequenceState& seq = sequences.at(SequenceFolderOf(runs[k], options.out_dir));
    if (!options.force && ReuseDoneRun(runs[k], options.out_dir, &rows[k])) {
      skipped[k] = 1;
      progress.Print(Describe(rows[k]) + "  [done before, skipped]");
      return;
    }
    ExecuteRun(runs[k], seq, options, timeout_s, &rows[k]);
    progress.Print(Describe(rows[k]));
  });

  BenchSummary summary;
  summary.runs = static_cast<int>(runs.size());
  for (size_t k = 0; k < rows.size(); ++k) {
    summary.ok += rows[k].status == kStatusOk;
    summary.skipped += skipped[k];
  }
  summary.not_ok = summary.runs - summary.ok;

  BenchHeader header;
  header.suite = suite.file;
  header.shard = options.shard.count > 1 ? options.shard.ToString() : "";
  header.runs_total = static_cast<int>(all.size());
  WriteAll(options.out_dir, header, rows);
  std::cerr << "dala bench: " << summary.ok << " ok, " << summary.not_ok << " not ok ("
            << summary.skipped << " reused); " << options.out_dir << "/report.html" << std::endl;
  return summary;
}

void MergeBench(const std::vector<std::string>& dirs, const std::string& out_dir_in) {
  if (dirs.empty()) throw Error() << "dala bench merge: give the folders to merge";
  const std::string out_dir = fs::absolute(out_dir_in).lexically_normal().string();
  CheckWritable(out_dir);
  BenchHeader merged;
  std::vector<BenchRunResult> rows;
  std::map<std::string, std::string> seen;  // run key -> folder.
  for (const std::string& dir : dirs) {
    BenchHeader header;
    const std::vector<BenchRunResult> part = ReadBenchResults(dir + "/results.json", &header);
    if (merged.suite.empty()) merged.suite = header.suite;
    merged.runs_total = std::max(merged.runs_total, header.runs_total);
    merged.merged_from.push_back(fs::absolute(dir).lexically_normal().string());
    std::error_code ec;
    const bool same = fs::equivalent(dir, out_dir, ec);
    for (const BenchRunResult& r : part) {
      const std::string key = RunKey(r);
      const auto [it, inserted] = seen.emplace(key, dir);
      if (!inserted) {
        throw Error() << "run " << key << " is in both " << it->second << " and " << dir
                      << "; merge the shards of one suite (each run once)";
      }
      if (!same && !r.run_dir.empty() && fs::is_directory(dir + "/" + r.run_dir)) {
        const std::string to = out_dir + "/" + r.run_dir;
        fs::remove_all(to, ec);
        CreateDirectories(to);
        fs::copy(dir + "/" + r.run_dir, to, fs::copy_options::recursive, ec);
        if (ec)
          throw Error() << "cannot copy " << dir << "/" << r.run_dir << " to " << to << ": "
                        << ec.message();
      }
      rows.push_back(r);
    }
  }
  if (merged.runs_total > 0 && static_cast<int>(rows.size()) != merged.runs_total) {
    std::cerr << "dala bench merge: warning: " << rows.size() << " of " << merged.runs_total
              << " runs; is a shard missing?" << std::endl;
  }
  WriteAll(out_dir, merged, rows);
  std::cerr << "dala bench merge: " << rows.size() << " runs from " << dirs.size()
            << " folders into " << out_dir << "/report.html" << std::endl;
}

}  // namespace dala::bench
