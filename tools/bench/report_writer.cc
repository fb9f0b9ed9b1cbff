#include "tools/bench/report_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <set>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "tools/bench/line_chart.h"
#include "tools/bench/summary.h"
#include "tools/html_escape.h"

namespace dala::bench {
namespace fs = std::filesystem;
namespace {

std::string Fixed(const std::optional<double>& v, int decimals) {
  if (!v) return "";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, *v);
  return buf;
}
std::string Int(const std::optional<int>& v) { return v ? std::to_string(*v) : ""; }

// One column of the CSV and of the full tables.
struct Column {
  const char* key;
  const char* title;  // Markdown / HTML header.
  std::function<std::string(const BenchRunResult&)> value;
};

const std::vector<Column>& Columns() {
  static const std::vector<Column> columns = {
      {"sequence", "sequence", [](const auto& r) { return r.sequence; }},
      {"config", "config", [](const auto& r) { return r.config; }},
      {"variant", "variant", [](const auto& r) { return r.variant; }},
      {"start", "start", [](const auto& r) { return Int(r.start); }},
      {"seed", "seed", [](const auto& r) { return Int(r.seed); }},
      {"estimator", "estimator", [](const auto& r) { return r.estimator; }},
      {"mode", "mode", [](const auto& r) { return r.mode; }},
      {"status", "status", [](const auto& r) { return r.status; }},
      {"ate_rmse", "ATE rmse [m]", [](const auto& r) { return Fixed(r.ate_rmse, 4); }},
      {"ate_median", "ATE median [m]", [](const auto& r) { return Fixed(r.ate_median, 4); }},
      {"ate_max", "ATE max [m]", [](const auto& r) { return Fixed(r.ate_max, 4); }},
      {"scale", "scale", [](const auto& r) { return Fixed(r.scale, 4); }},
      {"rpe_trans", "RPE 1f [m]", [](const auto& r) { return Fixed(r.rpe_trans, 4); }},
      {"rpe_rot_deg", "RPE 1f [deg]", [](const auto& r) { return Fixed(r.rpe_rot_deg, 3); }},
      {"rpe10_trans", "RPE 10f [m]", [](const auto& r) { return Fixed(r.rpe10_trans, 4); }},
      {"rpe10_rot_deg", "RPE 10f [deg]", [](const auto& r) { return Fixed(r.rpe10_rot_deg, 3); }},
      {"t_err_percent", "KITTI t [%]", [](const auto& r) { return Fixed(r.t_err_percent, 3); }},
      {"r_err_deg_per_100m", "KITTI r [deg/100m]",
       [](const auto& r) { return Fixed(r.r_err_deg_per_100m, 3); }},
      {"ms_median", "ms median", [](const auto& r) { return Fixed(r.ms_median, 1); }},
      {"ms_p95", "ms p95", [](const auto& r) { return Fixed(r.ms_p95, 1); }},
      {"ms_max", "ms max", [](const auto& r) { return Fixed(r.ms_max, 1); }},
      {"fps", "fps", [](const auto& r) { return Fixed(r.fps, 1); }},
      {"peak_rss_mb", "peak MiB", [](const auto& r) { return Fixed(r.peak_rss_mb, 0); }},
      {"wall_s", "wall [s]", [](const auto& r) { return Fixed(r.wall_s, 1); }},
      {"frames", "frames", [](const auto& r) { return Int(r.frames); }},
      {"pairs", "pairs", [](const auto& r) { return Int(r.pairs); }},
      {"path_length_m", "path [m]", [](const auto& r) { return Fixed(r.path_length_m, 1); }},
      {"landmarks", "landmarks", [](const auto& r) { return Int(r.landmarks); }},
      {"keyframes", "keyframes", [](const auto& r) { return Int(r.keyframes); }},
      {"keyframes_in_map", "in map", [](const auto& r) { return Int(r.keyframes_in_map); }},
      {"disparity_offset_px", "offset px",
       [](const auto& r) { return Fixed(r.disparity_offset_px, 3); }},
      {"tracking_failures", "lost", [](const auto& r) { return Int(r.tracking_failures); }},
      {"alignment", "align", [](const auto& r) { return r.alignment; }},
      {"error", "error", [](const auto& r) { return r.error; }},
  };
  return columns;
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string MdEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += "<br>";
    else
      out += c;
  }
  return out;
}

// Sequences and configurations in sorted order, and the runs (variants) of each pair.
using Cell = std::vector<const BenchRunResult*>;  // In run order.
struct Grid {
  std::vector<std::string> sequences, configs;
  std::map<std::pair<std::string, std::string>, Cell> cell;
  bool has_variants = false;  // Some pair has more than one run.
  const Cell& At(const std::string& s, const std::string& c) const {
    static const Cell kNone;
    const auto it = cell.find({s, c});
    return it == cell.end() ? kNone : it->second;
  }
  bool SequenceHasVariants(const std::string& s) const {
    return std::any_of(configs.begin(), configs.end(),
                       [&](const std::string& c) { return At(s, c).size() > 1; });
  }
};

Grid MakeGrid(const std::vector<BenchRunResult>& rows) {
  Grid g;
  std::set<std::string> seqs, cfgs;
  for (const BenchRunResult& r : rows) {
    seqs.insert(r.sequence);
    cfgs.insert(r.config);
    Cell& cell = g.cell[{r.sequence, r.config}];
    cell.push_back(&r);
    g.has_variants = g.has_variants || cell.size() > 1;
  }
  g.sequences.assign(seqs.begin(), seqs.end());
  g.configs.assign(cfgs.begin(), cfgs.end());
  return g;
}

// "start3" for a variant, "-" for a run without one (for table cells).
std::string VariantText(const std::string& variant) { return variant.empty() ? "-" : variant; }

// The metrics of the side-by-side tables: lower is better for all of them.
struct Metric {
  const char* title;
  std::function<std::optional<double>(const BenchRunResult&)> get;
  int decimals;
};
const std::vector<Metric>& SideBySideMetrics() {
  static const std::vector<Metric> metrics = {
      {"ATE RMSE [m]", [](const auto& r) { return r.ate_rmse; }, 4},
      {"RPE over 1 frame, RMSE [m]", [](const auto& r) { return r.rpe_trans; }, 4},
      {"RPE over 10 frames, RMSE [m]", [](const auto& r) { return r.rpe10_trans; }, 4},
      {"KITTI translation error [%]", [](const auto& r) { return r.t_err_percent; }, 3},
      {"per-frame time, median [ms]", [](const auto& r) { return r.ms_median; }, 1},
      {"per-frame time, p95 [ms]", [](const auto& r) { return r.ms_p95; }, 1},
      {"peak memory [MiB]",
       [](const auto& r) -> std::optional<double> {
         if (r.status == kStatusUnsupported || r.peak_rss_mb <= 0) return std::nullopt;
         return r.peak_rss_mb;
       },
       0},
  };
  return metrics;
}

// The value of a metric in a cell: its median over the cell's ok runs (the value itself for a
// cell of one run).
std::optional<double> CellValue(const Cell& cell, const Metric& m) {
  std::vector<double> values;
  for (const BenchRunResult* r : cell) {
    if (r->status != kStatusOk) continue;
    if (const auto v = m.get(*r)) values.push_back(*v);
  }
  return Percentile(values, 50.0);
}

int CountOk(const Cell& cell) {
  return static_cast<int>(std::count_if(
      cell.begin(), cell.end(), [](const BenchRunResult* r) { return r->status == kStatusOk; }));
}

// What a cell shows instead of a value when no run of it is ok: the common status, else "failed".
std::string CellStatus(const Cell& cell) {
  for (const BenchRunResult* r : cell) {
    if (r->status != cell.front()->status) return kStatusFailed;
  }
  return cell.front()->status;
}

// " (1/3 failed)" when some runs of a cell with ok runs are not ok: failures are counted, not
// hidden behind the median of the others.
std::string FailureNote(const Cell& cell) {
  const int failed = static_cast<int>(cell.size()) - CountOk(cell);
  if (failed == 0) return "";
  return " (" + std::to_string(failed) + "/" + std::to_string(cell.size()) + " failed)";
}

std::string CellText(const Cell& cell, const Metric& m) {
  if (cell.empty()) return "";
  if (CountOk(cell) == 0) return CellStatus(cell);
  const std::optional<double> v = CellValue(cell, m);
  return v ? Fixed(v, m.decimals) : "-";
}

// The best (lowest) cell value of a metric in a sequence row.
std::optional<double> Best(const Grid& g, const std::string& seq, const Metric& m) {
  std::optional<double> best;
  for (const std::string& c : g.configs) {
    const auto v = CellValue(g.At(seq, c), m);
    if (v && (!best || *v < *best)) best = v;
  }
  return best;
}

bool IsBest(const Cell& cell, const Metric& m, const std::optional<double>& best) {
  const auto v = CellValue(cell, m);
  return v && best && Fixed(v, m.decimals) == Fixed(best, m.decimals);
}

// The columns of the spread table (results.md, report.html, summary.csv).
struct SpreadColumn {
  const char* key;
  const char* title;
  std::function<std::string(const SpreadSummary&)> value;
};
const std::vector<SpreadColumn>& SpreadColumns() {
  static const std::vector<SpreadColumn> columns = {
      {"sequence", "sequence", [](const auto& s) { return s.sequence; }},
      {"config", "config", [](const auto& s) { return s.config; }},
      {"runs", "runs", [](const auto& s) { return std::to_string(s.runs); }},
      {"not_ok", "failed", [](const auto& s) { return std::to_string(s.runs - s.ok); }},
      {"ate_median", "ATE median [m]", [](const auto& s) { return Fixed(s.median, 4); }},
      {"ate_best", "best [m]", [](const auto& s) { return Fixed(s.best, 4); }},
      {"ate_best_variant", "best run",
       [](const auto& s) { return s.best ? VariantText(s.best_variant) : ""; }},
      {"ate_worst", "worst [m]", [](const auto& s) { return Fixed(s.worst, 4); }},
      {"ate_worst_variant", "worst run",
       [](const auto& s) { return s.worst ? VariantText(s.worst_variant) : ""; }},
      {"not_ok_runs", "failed runs",
       [](const auto& s) {
         std::string list;
         for (const std::string& f : s.not_ok) list += (list.empty() ? "" : ", ") + f;
         return list;
       }},
  };
  return columns;
}

// Names rather than numbers: left-aligned.
bool IsTextColumn(const SpreadColumn& c) {
  const std::string key = c.key;
  return key == "sequence" || key == "config" || key.find("variant") != std::string::npos ||
         key == "not_ok_runs";
}

const char* kSpreadTitle = "ATE RMSE over the runs of each sequence and configuration";
const char* kSpreadNote =
    "One row per sequence and configuration, over its runs (one per seed or start frame; "
    "a sequence without seeds or starts has one): failed counts runs that are not ok "
    "(failed, crashed, timeout, unsupported), which are not part of the median, best and worst.";

std::string MarkdownSpread(const std::vector<BenchRunResult>& rows) {
  std::string md = "\n## " + std::string(kSpreadTitle) + "\n\n" + kSpreadNote + "\n\n|";
  for (const SpreadColumn& c : SpreadColumns()) md += " " + std::string(c.title) + " |";
  md += "\n|";
  for (const SpreadColumn& c : SpreadColumns()) md += IsTextColumn(c) ? "---|" : "---:|";
  md += "\n";
  for (const SpreadSummary& s : SummarizeAte(rows)) {
    md += "|";
    for (const SpreadColumn& c : SpreadColumns()) md += " " + MdEscape(c.value(s)) + " |";
    md += "\n";
  }
  return md;
}

// ATE of every run, a row per (sequence, variant), a column per configuration.
struct VariantRow {
  std::string sequence, variant;
};
std::vector<VariantRow> VariantRows(const std::vector<BenchRunResult>& rows) {
  std::vector<VariantRow> out;
  std::set<std::string> seen;
  for (const BenchRunResult& r : rows) {  // Run order: sequences, then variants in order.
    if (seen.insert(r.sequence + "@" + r.variant).second) out.push_back({r.sequence, r.variant});
  }
  std::stable_sort(out.begin(), out.end(), [](const VariantRow& a, const VariantRow& b) {
    return a.sequence < b.sequence;
  });
  return out;
}

const BenchRunResult* RunOf(const Grid& g, const VariantRow& v, const std::string& config) {
  for (const BenchRunResult* r : g.At(v.sequence, config)) {
    if (r->variant == v.variant) return r;
  }
  return nullptr;
}

std::string RunAteText(const BenchRunResult* r) {
  if (r == nullptr) return "";
  if (r->status != kStatusOk) return r->status;
  return r->ate_rmse ? Fixed(r->ate_rmse, 4) : "-";
}

std::string MarkdownPerVariant(const Grid& g, const std::vector<BenchRunResult>& rows) {
  std::string md = "\n## ATE RMSE [m] of every run\n\n| sequence | run |";
  for (const std::string& c : g.configs) md += " " + c + " |";
  md += "\n|---|---|";
  for (size_t i = 0; i < g.configs.size(); ++i) md += "---:|";
  md += "\n";
  for (const VariantRow& v : VariantRows(rows)) {
    md += "| " + v.sequence + " | " + VariantText(v.variant) + " |";
    for (const std::string& c : g.configs) md += " " + RunAteText(RunOf(g, v, c)) + " |";
    md += "\n";
  }
  return md;
}

std::string Markdown(const BenchHeader& header, const std::vector<BenchRunResult>& rows) {
  const Grid g = MakeGrid(rows);
  std::string md = "# dala bench results\n\n";
  md += "Suite: `" + header.suite + "`" + (header.shard.empty() ? "" : ", shard " + header.shard) +
        ", " + std::to_string(rows.size()) + " of " + std::to_string(header.runs_total) +
        " runs. Metrics: docs/benchmarking.md. Best value of each row in **bold**.\n";
  if (g.has_variants) {
    md +=
        "\nSequences with seeds or start frames have several runs per configuration: the "
        "side-by-side tables give the median over the ok runs, and \"(k/n failed)\" when some "
        "were not ok.\n";
  }
  md += MarkdownSpread(rows);
  if (g.has_variants) md += MarkdownPerVariant(g, rows);
  for (const Metric& m : SideBySideMetrics()) {
    md += "\n## " + std::string(m.title) + (g.has_variants ? ", median" : "") + "\n\n| sequence |";
    for (const std::string& c : g.configs) md += " " + c + " |";
    md += "\n|---|";
    for (size_t i = 0; i < g.configs.size(); ++i) md += "---:|";
    md += "\n";
    for (const std::string& s : g.sequences) {
      const std::optional<double> best = Best(g, s, m);
      md += "| " + s + " |";
      for (const std::string& c : g.configs) {
        const Cell& cell = g.At(s, c);
        std::string text = CellText(cell, m);
        if (IsBest(cell, m, best)) text = "**" + text + "**";
        if (!cell.empty() && CountOk(cell) > 0) text += FailureNote(cell);
        md += " " + text + " |";
      }
      md += "\n";
    }
  }
  md += "\n## All runs\n\n|";
  for (const Column& c : Columns()) md += " " + std::string(c.title) + " |";
  md += "\n|";
  for (size_t i = 0; i < Columns().size(); ++i) md += "---|";
  md += "\n";
  for (const BenchRunResult& r : rows) {
    md += "|";
    for (const Column& c : Columns()) md += " " + MdEscape(c.value(r)) + " |";
    md += "\n";
  }
  return md;
}

const char* kCss = R"(
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 24px;
       color: #222; max-width: 1800px; }
h1 { margin-bottom: 4px; } h2 { margin-top: 36px; border-bottom: 1px solid #ddd; }
.meta { color: #555; margin-bottom: 16px; }
table { border-collapse: collapse; margin: 8px 0 20px 0; font-size: 14px; }
th, td { border: 1px solid #d0d0d0; padding: 4px 8px; text-align: right; vertical-align: top;
         white-space: nowrap; }
th { background: #f0f3f7; } td.name, th.name { text-align: left; font-weight: 600; }
td.best { background: #e3f4e1; font-weight: 700; }
.ok { color: #1a7f37; } .failed, .crashed, .timeout { color: #c62828; font-weight: 600; }
.unsupported { color: #8a6d00; }
tr.bad td { background: #fdf0f0; }
td.err { text-align: left; min-width: 260px; max-width: 420px; white-space: pre-wrap;
         font-size: 11px; color: #a00; }
.scroll { overflow-x: auto; }
.tables { display: flex; flex-wrap: wrap; gap: 8px 28px; }
.metric { font-size: 12px; color: #555; }
.cards { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
.card { border: 1px solid #ddd; border-radius: 6px; padding: 8px 12px; background: #fafafa; }
.card h3 { margin: 4px 0 8px 0; font-size: 16px; }
.card { flex: 0 1 640px; box-sizing: border-box; }
.card img { display: block; width: 100%; margin-bottom: 8px; }
.compare > div { flex: 1 1 640px; max-width: 900px; }
.compare img { width: 100%; }
div.err { color: #a00; white-space: pre-wrap; max-width: 860px; }
.small { font-size: 12px; color: #666; }
ul.failures { margin: 8px 0 16px 0; padding-left: 20px; } ul.failures li { margin-bottom: 6px; }
)";

std::string StatusSpan(const std::string& status) {
  return "<span class=\"" + EscapeHtml(status) + "\">" + EscapeHtml(status) + "</span>";
}

// A cell of a side-by-side table: the (median) value, or the status when no run is ok; the
// errors of the runs that are not ok in its tooltip.
std::string HtmlCell(const Cell& cell, const Metric& m, const std::optional<double>& best) {
  if (cell.empty()) return "<td></td>";
  std::string errors;
  for (const BenchRunResult* r : cell) {
    if (r->status == kStatusOk || r->error.empty()) continue;
    errors +=
        (errors.empty() ? "" : "\n") + (r->variant.empty() ? "" : r->variant + ": ") + r->error;
  }
  const std::string title = errors.empty() ? "" : " title=\"" + EscapeHtml(errors) + "\"";
  if (CountOk(cell) == 0) return "<td" + title + ">" + StatusSpan(CellStatus(cell)) + "</td>";
  const auto v = CellValue(cell, m);
  const std::string note = FailureNote(cell);
  return std::string("<td") + (IsBest(cell, m, best) ? " class=\"best\"" : "") + title + ">" +
         (v ? Fixed(v, m.decimals) : "&ndash;") +
         (note.empty() ? "" : "<span class=\"failed\">" + note + "</span>") + "</td>";
}

std::string HtmlSpread(const std::vector<BenchRunResult>& rows) {
  std::string h = "<h2>" + std::string(kSpreadTitle) + "</h2>\n<p class=\"small\">" +
                  EscapeHtml(kSpreadNote) + "</p>\n<table><tr>";
  for (const SpreadColumn& c : SpreadColumns()) h += "<th>" + EscapeHtml(c.title) + "</th>";
  h += "</tr>\n";
  for (const SpreadSummary& s : SummarizeAte(rows)) {
    h += std::string("<tr") + (s.ok < s.runs ? " class=\"bad\"" : "") + ">";
    for (const SpreadColumn& c : SpreadColumns()) {
      const std::string key = c.key;
      const std::string cls = key == "sequence" || key == "config" ? "name"
                              : key == "not_ok_runs"               ? "err"
                                                                   : "";
      h += "<td" + (cls.empty() ? "" : " class=\"" + cls + "\"") + ">" + EscapeHtml(c.value(s)) +
           "</td>";
    }
    h += "</tr>\n";
  }
  return h + "</table>\n";
}

std::string HtmlPerVariant(const Grid& g, const std::vector<BenchRunResult>& rows) {
  std::string h =
      "<h2>ATE RMSE [m] of every run</h2>\n<table><tr><th class=\"name\">sequence</th>"
      "<th class=\"name\">run</th>";
  for (const std::string& c : g.configs) h += "<th>" + EscapeHtml(c) + "</th>";
  h += "</tr>\n";
  for (const VariantRow& v : VariantRows(rows)) {
    h += "<tr><td class=\"name\">" + EscapeHtml(v.sequence) + "</td><td class=\"name\">" +
         EscapeHtml(VariantText(v.variant)) + "</td>";
    for (const std::string& c : g.configs) {
      const BenchRunResult* r = RunOf(g, v, c);
      const bool ok = r == nullptr || r->status == kStatusOk;
      h += "<td" + (ok ? std::string() : " title=\"" + EscapeHtml(r->error) + "\"") + ">" +
           (ok ? EscapeHtml(RunAteText(r)) : StatusSpan(r->status)) + "</td>";
    }
    h += "</tr>\n";
  }
  return h + "</table>\n";
}

// A run's name in the per-sequence section: the configuration, and its variant if any.
std::string RunLabel(const BenchRunResult& r) {
  return r.variant.empty() ? r.config : r.config + " @ " + r.variant;
}

// The runs of a sequence: those that are not ok in a compact list, then a card per ok run
// with its plots.
std::string HtmlSequenceRuns(const Grid& g, const std::string& s,
                             const std::function<bool(const std::string&)>& exists) {
  std::string h, failures;
  for (const std::string& c : g.configs) {
    for (const BenchRunResult* r : g.At(s, c)) {
      if (r->status == kStatusOk) continue;
      const std::string log = r->run_dir + "/log.txt";
      failures += "<li><b>" + EscapeHtml(RunLabel(*r)) + "</b> " + StatusSpan(r->status) +
                  (exists(log) ? " (<a href=\"" + EscapeHtml(log) + "\">log</a>)" : "") +
                  "<div class=\"err small\">" + EscapeHtml(r->error) + "</div></li>\n";
    }
  }
  if (!failures.empty()) h += "<ul class=\"failures\">\n" + failures + "</ul>\n";
  h += "<div class=\"cards\">\n";
  for (const std::string& c : g.configs) {
    for (const BenchRunResult* r : g.At(s, c)) {
      if (r->status != kStatusOk) continue;
      h += "<div class=\"card\"><h3>" + EscapeHtml(RunLabel(*r)) + " &middot; " +
           StatusSpan(r->status) + "</h3>\n";
      if (r->ate_rmse) {
        h += "<div class=\"small\">ATE " + Fixed(r->ate_rmse, 4) + " m &middot; RPE(1f) " +
             Fixed(r->rpe_trans, 4) + " m &middot; " + Fixed(r->ms_median, 1) + " ms median</div>";
      }
      if (!r->error.empty()) h += "<div class=\"err small\">" + EscapeHtml(r->error) + "</div>";
      for (const std::string* png : {&r->plot_trajectory, &r->plot_timing}) {
        if (exists(*png)) {
          h += "<img src=\"" + EscapeHtml(*png) + "\" alt=\"" + EscapeHtml(*png) + "\">\n";
        }
      }
      h += "<div class=\"small\">";
      for (const char* file : {"report.html", "log.txt", "report.json", "trajectory.txt"}) {
        const std::string rel = r->run_dir + "/" + file;
        if (exists(rel)) h += "<a href=\"" + EscapeHtml(rel) + "\">" + file + "</a> ";
      }
      h += "</div></div>\n";
    }
  }
  return h + "</div>\n";
}

std::string Html(const std::string& out_dir, const BenchHeader& header,
                 const std::vector<BenchRunResult>& rows,
                 const std::map<std::string, std::vector<std::string>>& sequence_pngs) {
  const Grid g = MakeGrid(rows);
  const std::function<bool(const std::string&)> exists = [&](const std::string& rel) {
    return !rel.empty() && fs::is_regular_file(fs::path(out_dir) / rel);
  };
  int ok = 0;
  for (const BenchRunResult& r : rows) ok += r.status == kStatusOk;
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\">\n"
      "<title>dala bench results</title>\n<style>" +
      std::string(kCss) + "</style></head><body>\n";
  h += "<h1>dala bench results</h1>\n<div class=\"meta\">suite <code>" + EscapeHtml(header.suite) +
       "</code>" + (header.shard.empty() ? "" : ", shard " + EscapeHtml(header.shard)) +
       " &middot; " + std::to_string(rows.size()) + " of " + std::to_string(header.runs_total) +
       " runs, " + std::to_string(ok) + " ok";
  if (!header.merged_from.empty()) {
    h += " &middot; merged from " + std::to_string(header.merged_from.size()) + " folders";
  }
  h += "</div>\n<p class=\"small\">ATE after SE(3) alignment for stereo and Sim(3) for mono; RPE "
       "over 1 and 10 frames; KITTI segment errors when the path is longer than 100 m; times "
       "per frame from each run's report.json. Best value of each row is highlighted. "
       "Definitions: docs/benchmarking.md and docs/evaluation.md.</p>\n";

  // Side by side: one table per metric, sequences x configurations.
  h += "<h2>Estimators side by side</h2>\n<div class=\"tables\">\n";
  for (const Metric& m : SideBySideMetrics()) {
    h += "<div><div class=\"metric\">" + std::string(m.title) +
         (g.has_variants ? ", median over the runs" : "") +
         "</div>\n<table><tr><th class=\"name\">sequence</th>";
    for (const std::string& c : g.configs) h += "<th>" + EscapeHtml(c) + "</th>";
    h += "</tr>\n";
    for (const std::string& s : g.sequences) {
      const std::optional<double> best = Best(g, s, m);
      h += "<tr><td class=\"name\"><a href=\"#seq-" + EscapeHtml(s) + "\">" + EscapeHtml(s) +
           "</a></td>";
      for (const std::string& c : g.configs) h += HtmlCell(g.At(s, c), m, best);
      h += "</tr>\n";
    }
    h += "</table></div>\n";
  }
  h += "</div>\n";
  h += HtmlSpread(rows);
  if (g.has_variants) h += HtmlPerVariant(g, rows);

  // Every run, every metric.
  // The error column right after the status, where it is seen.
  std::vector<const Column*> columns;
  for (const Column& c : Columns()) {
    if (std::string(c.key) != "error") columns.push_back(&c);
    if (std::string(c.key) == "status") columns.push_back(&Columns().back());
  }
  // Each row links to its run's report.html (`dala run`'s 3D view and charts), when written.
  h += "<h2>All runs</h2>\n<div class=\"scroll\"><table><tr><th>run</th>";
  for (const Column* c : columns) h += "<th>" + EscapeHtml(c->title) + "</th>";
  h += "</tr>\n";
  for (const BenchRunResult& r : rows) {
    h += std::string("<tr") + (r.status == kStatusOk ? "" : " class=\"bad\"") + ">";
    const std::string run_report = r.run_dir + "/report.html";
    h += exists(run_report) ? "<td><a href=\"" + EscapeHtml(run_report) + "\">3D</a></td>"
                            : std::string("<td></td>");
    for (const Column* column : columns) {
      const Column& c = *column;
      const std::string key = c.key;
      const std::string v = c.value(r);
      if (key == "sequence" || key == "config") {
        h += "<td class=\"name\">" + EscapeHtml(v) + "</td>";
      } else if (key == "status") {
        h += "<td>" + StatusSpan(v) + "</td>";
      } else if (key == "error") {
        h += "<td class=\"err\">" + EscapeHtml(v) + "</td>";
      } else {
        h += "<td>" + EscapeHtml(v) + "</td>";
      }
    }
    h += "</tr>\n";
  }
  h += "</table></div>\n";

  // Per sequence: the comparison charts, then each run's plots.
  for (const std::string& s : g.sequences) {
    h += "<h2 id=\"seq-" + EscapeHtml(s) + "\">" + EscapeHtml(s) +
         "</h2>\n<div class=\"cards compare\">";
    const auto pngs = sequence_pngs.find(s);
    for (size_t i = 0; pngs != sequence_pngs.end() && i < pngs->second.size(); ++i) {
      const std::string& png = pngs->second[i];
      if (exists(png)) {
        h += "<div><img src=\"" + EscapeHtml(png) + "\" alt=\"" + EscapeHtml(png) + "\"></div>";
      }
    }
    h += "</div>\n";
    h += HtmlSequenceRuns(g, s, exists);
  }
  h += "</body></html>\n";
  return h;
}

// The spread of the ATE over a sequence's runs: per configuration (x), a dot per run coloured
// by its variant, and the median as a bar. Failed runs have no dot; the x labels count them.
void DrawSpread(const Grid& g, const std::string& s, const std::string& png) {
  std::vector<std::string> variants;  // In run order.
  for (const std::string& c : g.configs) {
    for (const BenchRunResult* r : g.At(s, c)) {
      if (std::find(variants.begin(), variants.end(), r->variant) == variants.end()) {
        variants.push_back(r->variant);
      }
    }
  }
  std::vector<ChartSeries> dots(variants.size());
  ChartSeries median("median", {}, {}, ChartStyle::kSegments);
  median.colour = cv::Scalar(40, 40, 40);
  LineChartOptions o;
  for (size_t v = 0; v < variants.size(); ++v) {
    dots[v].name = VariantText(variants[v]);
    dots[v].style = ChartStyle::kPoints;
  }
  // Variants side by side within a category, so that each dot can be told apart.
  const double width = 0.5;
  const auto offset = [&](size_t v) {
    return variants.size() < 2 ? 0.0 : -width / 2 + width * v / (variants.size() - 1.0);
  };
  for (size_t i = 0; i < g.configs.size(); ++i) {
    const Cell& cell = g.At(s, g.configs[i]);
    const int failed = static_cast<int>(cell.size()) - CountOk(cell);
    o.x_categories.push_back(g.configs[i] +
                             (failed > 0 ? " (" + std::to_string(failed) + " failed)" : ""));
    for (const BenchRunResult* r : cell) {
      if (r->status != kStatusOk || !r->ate_rmse) continue;
      const size_t v = static_cast<size_t>(std::find(variants.begin(), variants.end(), r->variant) -
                                           variants.begin());
      dots[v].x.push_back(static_cast<double>(i) + offset(v));
      dots[v].y.push_back(*r->ate_rmse);
    }
    const Metric ate{"", [](const BenchRunResult& r) { return r.ate_rmse; }, 4};
    if (const auto m = CellValue(cell, ate)) {
      median.x.insert(median.x.end(), {i - width / 2 - 0.1, i + width / 2 + 0.1});
      median.y.insert(median.y.end(), {*m, *m});
    }
  }
  dots.insert(dots.begin(), median);  // First, so that the dots are drawn over the bar.
  o.title = s + ": ATE RMSE of every run (dots) and the median (bar)";
  o.x_label = "configuration";
  o.y_label = "ATE RMSE [m]";
  o.legend_outside = true;
  o.width = std::max(900, 160 * static_cast<int>(g.configs.size()) + 200);
  DrawLineChart(dots, o, png);
}

// The runs drawn in a sequence's comparison charts: each configuration's first ok run (one
// curve per configuration stays readable; the spread plot shows all runs).
std::vector<const BenchRunResult*> ComparedRuns(const Grid& g, const std::string& s) {
  std::vector<const BenchRunResult*> runs;
  for (const std::string& c : g.configs) {
    for (const BenchRunResult* r : g.At(s, c)) {
      if (r->status != kStatusOk) continue;
      runs.push_back(r);
      break;
    }
  }
  return runs;
}

// The per-sequence charts; returns the relative paths drawn, per sequence.
std::map<std::string, std::vector<std::string>> DrawComparisons(
    const std::string& out_dir, const std::vector<BenchRunResult>& rows,
    const std::map<std::string, RunSeries>& series) {
  const Grid g = MakeGrid(rows);
  CreateDirectories(out_dir + "/plots");
  std::map<std::string, std::vector<std::string>> pngs;
  for (const std::string& s : g.sequences) {
    const bool variants = g.SequenceHasVariants(s);
    if (variants) {
      const std::string rel = "plots/" + s + "_ate_spread.png";
      DrawSpread(g, s, out_dir + "/" + rel);
      pngs[s].push_back(rel);
    }
    std::vector<ChartSeries> ate, time;
    for (const BenchRunResult* r : ComparedRuns(g, s)) {
      const auto it = series.find(r->run_dir);
      if (it == series.end()) continue;
      const std::string name = variants ? RunLabel(*r) : r->config;
      if (!it->second.ate_m.empty()) ate.push_back({name, it->second.distance_m, it->second.ate_m});
      if (!it->second.ms_total.empty()) {
        time.push_back({name, it->second.frame, it->second.ms_total});
      }
    }
    const std::string which = variants ? ", first run of each configuration" : "";
    if (!ate.empty()) {
      LineChartOptions o;
      o.title = s + ": ATE along the path (aligned; se3 stereo, sim3 mono)" + which;
      o.x_label = "distance travelled along the ground truth [m]";
      o.y_label = "ATE [m]";
      const std::string rel = "plots/" + s + "_ate.png";
      DrawLineChart(ate, o, out_dir + "/" + rel);
      pngs[s].push_back(rel);
    }
    if (!time.empty()) {
      LineChartOptions o;
      o.title = s + ": per-frame time (total)" + which;
      o.x_label = "frame";
      o.y_label = "time [ms]";
      const std::string rel = "plots/" + s + "_time.png";
      DrawLineChart(time, o, out_dir + "/" + rel);
      pngs[s].push_back(rel);
    }
  }
  return pngs;
}

}  // namespace

std::string ResultsCsv(const std::vector<BenchRunResult>& rows) {
  std::string csv;
  for (const Column& c : Columns()) csv += (csv.empty() ? "" : ",") + std::string(c.key);
  csv += "\n";
  for (const BenchRunResult& r : rows) {
    std::string line;
    for (size_t i = 0; i < Columns().size(); ++i) {
      line += (i ? "," : "") + CsvField(Columns()[i].value(r));
    }
    csv += line + "\n";
  }
  return csv;
}

std::string SummaryCsv(const std::vector<BenchRunResult>& rows) {
  std::string csv;
  for (const SpreadColumn& c : SpreadColumns())
    csv += (csv.empty() ? "" : ",") + std::string(c.key);
  csv += "\n";
  for (const SpreadSummary& s : SummarizeAte(rows)) {
    std::string line;
    for (size_t i = 0; i < SpreadColumns().size(); ++i) {
      line += (i ? "," : "") + CsvField(SpreadColumns()[i].value(s));
    }
    csv += line + "\n";
  }
  return csv;
}

void WriteBenchOutputs(const std::string& out_dir, const BenchHeader& header,
                       const std::vector<BenchRunResult>& rows,
                       const std::map<std::string, RunSeries>& series) {
  nlohmann::json j;
  j["dala_bench"] = 1;
  j["suite"] = header.suite;
  j["shard"] = header.shard.empty() ? nlohmann::json(nullptr) : nlohmann::json(header.shard);
  j["runs_total"] = header.runs_total;
  if (!header.merged_from.empty()) j["merged_from"] = header.merged_from;
  j["runs"] = nlohmann::json::array();
  for (const BenchRunResult& r : rows) j["runs"].push_back(ToJson(r));
  j["summary"] = nlohmann::json::array();
  for (const SpreadSummary& s : SummarizeAte(rows)) j["summary"].push_back(AteSummaryJson(s));
  WriteFileAtomically(out_dir + "/results.json",
                      [&](std::ostream& os) { os << j.dump(2) << "\n"; });
  WriteFileAtomically(out_dir + "/results.csv", [&](std::ostream& os) { os << ResultsCsv(rows); });
  WriteFileAtomically(out_dir + "/results.md",
                      [&](std::ostream& os) { os << Markdown(header, rows); });
  WriteFileAtomically(out_dir + "/summary.csv", [&](std::ostream& os) { os << SummaryCsv(rows); });
  const auto pngs = DrawComparisons(out_dir, rows, series);
  WriteFileAtomically(out_dir + "/report.html",
                      [&](std::ostream& os) { os << Html(out_dir, header, rows, pngs); });
}

std::vector<BenchRunResult> ReadBenchResults(const std::string& path, BenchHeader* header) {
  std::ifstream is(path);
  if (!is) {
    throw Error() << path << ": missing; give folders written by `dala bench ... --out DIR`";
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(is);
  } catch (const nlohmann::json::exception& e) {
    throw Error() << path << ": not JSON: " << e.what();
  }
  if (!j.is_object() || !j.contains("runs") || !j["runs"].is_array()) {
    throw Error() << path << ": expected {\"runs\": [...]} as written by dala bench";
  }
  header->suite = j.value("suite", "");
  header->shard =
      j.contains("shard") && j["shard"].is_string() ? j["shard"].get<std::string>() : "";
  header->runs_total = j.value("runs_total", 0);
  std::vector<BenchRunResult> rows;
  for (size_t i = 0; i < j["runs"].size(); ++i) {
    rows.push_back(
        BenchRunResultFromJson(j["runs"][i], path + ": runs[" + std::to_string(i) + "]"));
  }
  return rows;
}

}  // namespace dala::bench
