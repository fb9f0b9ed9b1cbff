#ifndef DALA_TOOLS_BENCH_SUMMARY_H_
#define DALA_TOOLS_BENCH_SUMMARY_H_

// The spread of a metric over the variants (seeds, start frames) of each (sequence,
// configuration): one run is one sample of what a user gets, so the tables give how many runs
// there were, how many failed, the median, and the best and worst with the variant that gave
// them.

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "tools/bench/run_result.h"

namespace dala::bench {

struct SpreadSummary {
  std::string sequence;
  std::string config;
  int runs = 0;  // Variants recorded.
  int ok = 0;    // Runs with status ok.
  // The runs that are not ok, "VARIANT: status" ("status" alone for a run without a variant),
  // in run order. They count as failures: they are not part of the median, best or worst.
  std::vector<std::string> not_ok;
  int values = 0;  // Ok runs with a value of the metric (the sample of the statistics).
  std::optional<double> median;  // numpy's median: the mean of the two middle values if even.
  std::optional<double> best;    // Lowest.
  std::optional<double> worst;   // Highest.
  std::string best_variant;      // Its variant (empty for a run without one); the first on ties.
  std::string worst_variant;
};

// One summary per (sequence, configuration) present in `rows`, sorted by (sequence,
// configuration); `rows` in run order. `metric` returns the value of an ok run (lower is
// better), nullopt when it has none.
std::vector<SpreadSummary> Summarize(
    const std::vector<BenchRunResult>& rows,
    const std::function<std::optional<double>(const BenchRunResult&)>& metric);

// Of the ATE RMSE, the summary that results.json, summary.csv and the tables give.
std::vector<SpreadSummary> SummarizeAte(const std::vector<BenchRunResult>& rows);

// A summary of SummarizeAte as results.json gives it (keys ate_median, ate_worst_variant, ...).
nlohmann::json AteSummaryJson(const SpreadSummary& s);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_SUMMARY_H_
