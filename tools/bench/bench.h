#ifndef DALA_TOOLS_BENCH_BENCH_H_
#define DALA_TOOLS_BENCH_BENCH_H_

// `dala bench`: runs every sequence x configuration of a suite as `dala run` subprocesses,
// evaluates each run against ground truth with core/eval, and writes results.json/csv/md and
// report.html (tools/bench/report_writer.h). docs/benchmarking.md is the user's guide.
//
// Layout of the output folder DIR:
//   DIR/sequences/NAME[@seedS]/  rendered presets (`dala synth`), reused when already there
//   DIR/runs/SEQ[@VARIANT]/CONFIG/  (VARIANT: seedS or startF, see suite.h)
//                                dala run's outputs, log.txt (its stdout+stderr), eval.png,
//                                timing.png, bench_series.json, bench_done.json (the done marker)
//   DIR/plots/                   per-sequence comparison charts
//   DIR/results.{json,csv,md}, DIR/summary.csv, DIR/report.html

#include <string>
#include <vector>

#include "tools/bench/suite.h"

namespace dala::bench {

struct BenchOptions {
  std::string out_dir;    // DIR.
  std::string dala_path;  // The `dala` executable run as `dala synth` / `dala run`.
  int jobs = 1;           // Subprocesses at once.
  Shard shard;            // Slice of the sorted run list to run.
  bool force = false;     // Rerun runs that are done.
  double timeout_s = -1;  // Per run; < 0: the suite's timeout_s.

  bool IsValid(std::string* why) const;
};

struct BenchSummary {
  int runs = 0;     // Runs of this shard.
  int ok = 0;       // Finished with status ok.
  int skipped = 0;  // Already done, not rerun.
  int not_ok = 0;   // Failed, crashed, timed out or unsupported.
};

// Runs the suite (throws dala::Error on an unwritable output folder or a missing `dala`).
// Progress lines go to stderr. Runs that fail are recorded, not thrown.
BenchSummary RunBench(const BenchSuite& suite, const BenchOptions& options);

// Gathers the outputs of several `dala bench` folders (shards) into `out_dir`: copies their
// runs/ folders there and writes one results.json/csv/md and report.html. Throws dala::Error on
// a folder without results.json or a run present in two folders.
void MergeBench(const std::vector<std::string>& dirs, const std::string& out_dir);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_BENCH_H_
