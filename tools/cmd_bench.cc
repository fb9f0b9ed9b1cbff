// `dala bench`: runs a suite of sequences x estimator configurations as `dala run` subprocesses
// and gathers ATE / RPE / KITTI errors, timings and memory into results.json/csv/md and a static
// report.html. docs/benchmarking.md is the guide.
#include <gflags/gflags.h>
#include <unistd.h>

#include <iostream>
#include <mutex>
#include <string>
#include <vector>

#include "core/error.h"
#include "tools/bench/bench.h"
#include "tools/bench/suite.h"
#include "tools/command.h"

DECLARE_string(out);  // Defined once for all commands (tools/flag_out.cc or cmd_synth.cc).
DEFINE_int32(jobs, 1, "bench: number of runs (subprocesses) at once");
DEFINE_string(shard, "0/1",
              "bench: run only shard i of n (i/n, 0-based): run k of the sorted run list "
              "belongs to shard k mod n");
DEFINE_bool(force, false, "bench: rerun runs that are already done (report.json + done marker)");
DEFINE_string(dala, "",
              "bench: the dala executable to run as `dala synth` / `dala run` (default: this "
              "binary)");
DEFINE_string(dataset, "",
              "bench: a dataset folder to add to the suite's sequences (repeatable: "
              "--dataset A --dataset B)");
DEFINE_string(starts, "",
              "bench: start frames of every dataset sequence (suite and --dataset), overriding "
              "the suite's `starts`: a count N (frames 0..N-1) or a list 0,5,10 (one frame F: "
              "\"F,\"); each start is one run per configuration (`dala run --first_frame`)");
DEFINE_double(run_timeout, -1.0,
              "bench: per-run timeout in seconds (0 = none; < 0: the suite's timeout_s)");

namespace dala {
namespace {

// gflags keeps the last value of a repeated flag; a validator sees every one of them.
std::vector<std::string>& DatasetFlags() {
  static std::vector<std::string> values;
  return values;
}
bool CollectDataset(const char*, const std::string& value) {
  if (!value.empty()) DatasetFlags().push_back(value);
  return true;
}
const bool dataset_validator = gflags::RegisterFlagValidator(&FLAGS_dataset, &CollectDataset);

std::string SelfPath() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) throw Error() << "cannot find the dala executable; give --dala PATH";
  return std::string(buf, static_cast<size_t>(n));
}

int RunBenchCommand(const std::vector<std::string>& args) {
  (void)dataset_validator;
  if (args.empty()) {
    throw Error() << "usage: dala bench SUITE.yaml --out DIR [...] (the default suite is "
                  << "benchmarks/default.yaml); see `dala bench --help`";
  }
  if (FLAGS_out.empty()) {
    throw Error() << "--out DIR is required (the output folder); see `dala bench --help`";
  }
  if (!args.empty() && args[0] == "merge") {
    const std::vector<std::string> dirs(args.begin() + 1, args.end());
    if (dirs.empty()) throw Error() << "usage: dala bench merge DIR... --out DIR";
    bench::MergeBench(dirs, FLAGS_out);
    return 0;
  }
  if (args.size() != 1) {
    throw Error() << "expected one suite file (e.g. benchmarks/default.yaml), got " << args.size()
                  << " arguments; see `dala bench --help`";
  }
  bench::BenchSuite suite = bench::LoadBenchSuite(args[0]);
  for (const std::string& note : suite.skipped) std::cerr << "dala bench: " << note << std::endl;
  for (const std::string& folder : DatasetFlags()) bench::AddDatasetSequence(folder, &suite);
  if (!FLAGS_starts.empty()) {
    const std::vector<int> starts = bench::ParseStartsFlag(FLAGS_starts);
    if (bench::SetDatasetStarts(starts, &suite) == 0) {
      std::cerr << "dala bench: --starts: the suite has no dataset sequence (rendered presets "
                << "take `seeds` in the suite file); nothing changed" << std::endl;
    }
  }

  bench::BenchOptions options;
  options.out_dir = FLAGS_out;
  options.dala_path = FLAGS_dala.empty() ? SelfPath() : FLAGS_dala;
  options.jobs = FLAGS_jobs;
  options.shard = bench::ParseShard(FLAGS_shard);
  options.force = FLAGS_force;
  options.timeout_s = FLAGS_run_timeout;
  std::string why;
  if (!options.IsValid(&why)) throw Error() << why;
  bench::RunBench(suite, options);
  return 0;
}

const CommandRegistrar registrar(
    {"bench", "run a benchmark suite (sequences x estimators) and report ATE/RPE/time/memory",
     "dala bench SUITE.yaml --out DIR [--jobs N] [--shard i/n] [--force] [--dala PATH]\n"
     "                  [--dataset FOLDER]... [--starts N|a,b,...] [--run_timeout S]\n"
     "       dala bench merge DIR... --out DIR\n\n"
     "Runs every sequence x configuration of the suite as a `dala run` subprocess (a run that\n"
     "fails, crashes or times out is recorded and the others go on); a sequence with `seeds`\n"
     "(rendered) or `starts` (dataset, or --starts) runs once per seed or start frame, and the\n"
     "tables give the median, best and worst over them. Preset sequences are rendered\n"
     "once per seed with `dala synth` into DIR/sequences, and each trajectory is re-evaluated\n"
     "against ground truth (ATE with SE(3) alignment for stereo and Sim(3) for mono, RPE over\n"
     "1 and 10 frames, KITTI segment errors); outputs: DIR/results.json, results.csv,\n"
     "summary.csv, results.md and a static DIR/report.html with the plots. Finished runs are\n"
     "reused unless --force. `merge` gathers the folders of several shards into one report.\n"
     "Exit status 0 when every run was recorded (whatever its status), 2 on a bad suite, flag\n"
     "or output folder.\n"
     "Suite format, outputs and the Slurm / Kubernetes recipes: docs/benchmarking.md.\n\n"
     "examples:\n"
     "  dala bench benchmarks/default.yaml --out bench_out --jobs 2\n"
     "  dala bench benchmarks/default.yaml --out bench_out --dataset /data/kitti/sequences/06\n"
     "  dala bench suite.yaml --out bench_out --dataset /data/kitti/sequences/06 --starts 10\n"
     "  dala bench suite.yaml --out part3 --shard 3/8 && dala bench merge part* --out all",
     &RunBenchCommand, __FILE__});

}  // namespace
}  // namespace dala
