#ifndef DALA_TOOLS_BENCH_REPORT_WRITER_H_
#define DALA_TOOLS_BENCH_REPORT_WRITER_H_

// The outputs of `dala bench` in its output folder DIR, all written atomically:
//   results.json  {"dala_bench": 1, "suite", "shard", "runs_total", "runs": [row, ...],
//                  "summary": [per (sequence, configuration): runs, failures, ATE median, best,
//                  worst and which run]}
//   results.csv   one line per run, the columns of docs/benchmarking.md
//   summary.csv   one line per (sequence, configuration): the "summary" of results.json
//   results.md    the spread table, the ATE of every run (when sequences have several),
//                 side-by-side tables (sequences x configurations, medians over the runs) and
//                 the full table
//   report.html   static page: the tables and every plot (relative links, opens from disk);
//                 each run's row and card link the run's own report.html when it wrote one
//   plots/SEQ_ate.png, plots/SEQ_time.png: all configurations of a sequence on one chart;
//   plots/SEQ_ate_spread.png: the ATE of every run per configuration, for a sequence with
//   several runs per configuration (seeds, start frames).

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/bench/evaluate_run.h"
#include "tools/bench/run_result.h"

namespace dala::bench {

struct BenchHeader {
  std::string suite;                     // Suite file (or "merged").
  std::string shard;                     // "i/n", or empty for merged / unsharded output.
  int runs_total = 0;                    // Runs in the full (unsharded) list.
  std::vector<std::string> merged_from;  // Folders merged by `dala bench merge`.
};

// Writes every output. `rows` are sorted by index; `series` is keyed by the row's run_dir (runs
// without an entry get no curve in the per-sequence plots). Throws dala::Error naming a file
// that cannot be written.
void WriteBenchOutputs(const std::string& out_dir, const BenchHeader& header,
                       const std::vector<BenchRunResult>& rows,
                       const std::map<std::string, RunSeries>& series);

// Reads DIR/results.json back (for merge). Throws dala::Error naming the file.
std::vector<BenchRunResult> ReadBenchResults(const std::string& path, BenchHeader* header);

// The CSV text (exposed for tests).
std::string ResultsCsv(const std::vector<BenchRunResult>& rows);
// summary.csv: the ATE over the runs of each (sequence, configuration), tools/bench/summary.h.
std::string SummaryCsv(const std::vector<BenchRunResult>& rows);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_REPORT_WRITER_H_
