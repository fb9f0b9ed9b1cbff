#include "tools/bench/summary.h"

#include <map>
#include <utility>

#include "tools/bench/evaluate_run.h"

namespace dala::bench {

std::vector<SpreadSummary> Summarize(
    const std::vector<BenchRunResult>& rows,
    const std::function<std::optional<double>(const BenchRunResult&)>& metric) {
  std::map<std::pair<std::string, std::string>, SpreadSummary> cells;  // Sorted by the pair.
  std::map<std::pair<std::string, std::string>, std::vector<double>> values;
  for (const BenchRunResult& r : rows) {
    const std::pair<std::string, std::string> key{r.sequence, r.config};
    SpreadSummary& s = cells[key];
    s.sequence = r.sequence;
    s.config = r.config;
    ++s.runs;
    if (r.status != kStatusOk) {
      s.not_ok.push_back(r.variant.empty() ? r.status : r.variant + ": " + r.status);
      continue;
    }
    ++s.ok;
    const std::optional<double> v = metric(r);
    if (!v) continue;
    values[key].push_back(*v);
    // Strict comparisons: the first run in run order wins a tie, whatever the completion order.
    if (!s.best || *v < *s.best) s.best = v, s.best_variant = r.variant;
    if (!s.worst || *v > *s.worst) s.worst = v, s.worst_variant = r.variant;
  }
  std::vector<SpreadSummary> out;
  for (auto& [key, s] : cells) {
    const std::vector<double>& v = values[key];
    s.values = static_cast<int>(v.size());
    s.median = Percentile(v, 50.0);
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<SpreadSummary> SummarizeAte(const std::vector<BenchRunResult>& rows) {
  return Summarize(rows, [](const BenchRunResult& r) { return r.ate_rmse; });
}

nlohmann::json AteSummaryJson(const SpreadSummary& s) {
  const auto number = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  return {{"sequence", s.sequence},
          {"config", s.config},
          {"runs", s.runs},
          {"ok", s.ok},
          {"not_ok", s.runs - s.ok},
          {"not_ok_runs", s.not_ok},
          {"ate_values", s.values},
          {"ate_median", number(s.median)},
          {"ate_best", number(s.best)},
          {"ate_best_variant", s.best_variant},
          {"ate_worst", number(s.worst)},
          {"ate_worst_variant", s.worst_variant}};
}

}  // namespace dala::bench
