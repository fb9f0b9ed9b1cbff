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

std::string HtmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
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

// Sequences and configurations in sorted order, and the row of each pair.
struct Grid {
  std::vector<std::string> sequences, configs;
  std::map<std::pair<std::string, std::string>, const BenchRunResult*> cell;
  const BenchRunResult* At(const std::string& s, const std::string& c) const {
    const auto it = cell.find({s, c});
    return it == cell.end() ? nullptr : it->second;
  }
};

Grid MakeGrid(const std::vector<BenchRunResult>& rows) {
  Grid g;
  std::set<std::string> seqs, cfgs;
  for (const BenchRunResult& r : rows) {
    seqs.insert(r.sequence);
    cfgs.insert(r.config);
    g.cell[{r.sequence, r.config}] = &r;
  }
  g.sequences.assign(seqs.begin(), seqs.end());
  g.configs.assign(cfgs.begin(), cfgs.end());
  return g;
}

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

std::string CellText(const BenchRunResult* r, const Metric& m) {
  if (r == nullptr) return "";
  if (r->status != kStatusOk) return r->status;
  const std::optional<double> v = m.get(*r);
  return v ? Fixed(v, m.decimals) : "-";
}

// The best (lowest) value of a metric in a sequence row, among ok runs.
std::optional<double> Best(const Grid& g, const std::string& seq, const Metric& m) {
  std::optional<double> best;
  for (const std::string& c : g.configs) {
    const BenchRunResult* r = g.At(seq, c);
    if (r == nullptr || r->status != kStatusOk) continue;
    const auto v = m.get(*r);
    if (v && (!best || *v < *best)) best = v;
  }
  return best;
}

std::string Markdown(const BenchHeader& header, const std::vector<BenchRunResult>& rows) {
  const Grid g = MakeGrid(rows);
  std::string md = "# dala bench results\n\n";
  md += "Suite: `" + header.suite + "`" + (header.shard.empty() ? "" : ", shard " + header.shard) +
        ", " + std::to_string(rows.size()) + " of " + std::to_string(header.runs_total) +
        " runs. Metrics: docs/benchmarking.md. Best value of each row in **bold**.\n";
  for (const Metric& m : SideBySideMetrics()) {
    md += "\n## " + std::string(m.title) + "\n\n| sequence |";
    for (const std::string& c : g.configs) md += " " + c + " |";
    md += "\n|---|";
    for (size_t i = 0; i < g.configs.size(); ++i) md += "---:|";
    md += "\n";
    for (const std::string& s : g.sequences) {
      const std::optional<double> best = Best(g, s, m);
      md += "| " + s + " |";
      for (const std::string& c : g.configs) {
        const BenchRunResult* r = g.At(s, c);
        std::string text = CellText(r, m);
        if (r != nullptr && r->status == kStatusOk && best && m.get(*r) &&
            Fixed(m.get(*r), m.decimals) == Fixed(best, m.decimals)) {
          text = "**" + text + "**";
        }
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
  return "<span class=\"" + HtmlEscape(status) + "\">" + HtmlEscape(status) + "</span>";
}

std::string Html(const std::string& out_dir, const BenchHeader& header,
                 const std::vector<BenchRunResult>& rows,
                 const std::map<std::string, std::string>& compare_ate,
                 const std::map<std::string, std::string>& compare_time) {
  const Grid g = MakeGrid(rows);
  const auto exists = [&](const std::string& rel) {
    return !rel.empty() && fs::is_regular_file(fs::path(out_dir) / rel);
  };
  int ok = 0;
  for (const BenchRunResult& r : rows) ok += r.status == kStatusOk;
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\">\n"
      "<title>dala bench results</title>\n<style>" +
      std::string(kCss) + "</style></head><body>\n";
  h += "<h1>dala bench results</h1>\n<div class=\"meta\">suite <code>" + HtmlEscape(header.suite) +
       "</code>" + (header.shard.empty() ? "" : ", shard " + HtmlEscape(header.shard)) +
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
         "</div>\n<table><tr><th class=\"name\">sequence</th>";
    for (const std::string& c : g.configs) h += "<th>" + HtmlEscape(c) + "</th>";
    h += "</tr>\n";
    for (const std::string& s : g.sequences) {
      const std::optional<double> best = Best(g, s, m);
      h += "<tr><td class=\"name\"><a href=\"#seq-" + HtmlEscape(s) + "\">" + HtmlEscape(s) +
           "</a></td>";
      for (const std::string& c : g.configs) {
        const BenchRunResult* r = g.At(s, c);
        if (r == nullptr) {
          h += "<td></td>";
        } else if (r->status != kStatusOk) {
          h += "<td title=\"" + HtmlEscape(r->error) + "\">" + StatusSpan(r->status) + "</td>";
        } else {
          const auto v = m.get(*r);
          const bool is_best = v && best && Fixed(v, m.decimals) == Fixed(best, m.decimals);
          h += std::string("<td") + (is_best ? " class=\"best\"" : "") + ">" +
               (v ? Fixed(v, m.decimals) : "&ndash;") + "</td>";
        }
      }
      h += "</tr>\n";
    }
    h += "</table></div>\n";
  }
  h += "</div>\n";

  // Every run, every metric.
  // The error column right after the status, where it is seen.
  std::vector<const Column*> columns;
  for (const Column& c : Columns()) {
    if (std::string(c.key) != "error") columns.push_back(&c);
    if (std::string(c.key) == "status") columns.push_back(&Columns().back());
  }
  h += "<h2>All runs</h2>\n<div class=\"scroll\"><table><tr>";
  for (const Column* c : columns) h += "<th>" + HtmlEscape(c->title) + "</th>";
  h += "</tr>\n";
  for (const BenchRunResult& r : rows) {
    h += std::string("<tr") + (r.status == kStatusOk ? "" : " class=\"bad\"") + ">";
    for (const Column* column : columns) {
      const Column& c = *column;
      const std::string key = c.key;
      const std::string v = c.value(r);
      if (key == "sequence" || key == "config") {
        h += "<td class=\"name\">" + HtmlEscape(v) + "</td>";
      } else if (key == "status") {
        h += "<td>" + StatusSpan(v) + "</td>";
      } else if (key == "error") {
        h += "<td class=\"err\">" + HtmlEscape(v) + "</td>";
      } else {
        h += "<td>" + HtmlEscape(v) + "</td>";
      }
    }
    h += "</tr>\n";
  }
  h += "</table></div>\n";

  // Per sequence: the comparison charts, then each run's plots.
  for (const std::string& s : g.sequences) {
    h += "<h2 id=\"seq-" + HtmlEscape(s) + "\">" + HtmlEscape(s) +
         "</h2>\n<div class=\"cards "
         "compare\">";
    for (const auto* m : {&compare_ate, &compare_time}) {
      const auto it = m->find(s);
      if (it != m->end() && exists(it->second)) {
        h += "<div><img src=\"" + HtmlEscape(it->second) + "\" alt=\"" + HtmlEscape(it->second) +
             "\"></div>";
      }
    }
    h += "</div>\n";
    // Runs without plots in a compact list, then a card per run with its plots.
    std::string failures;
    for (const std::string& c : g.configs) {
      const BenchRunResult* r = g.At(s, c);
      if (r == nullptr || r->status == kStatusOk) continue;
      const std::string log = r->run_dir + "/log.txt";
      failures += "<li><b>" + HtmlEscape(c) + "</b> " + StatusSpan(r->status) +
                  (exists(log) ? " (<a href=\"" + HtmlEscape(log) + "\">log</a>)" : "") +
                  "<div class=\"err small\">" + HtmlEscape(r->error) + "</div></li>\n";
    }
    if (!failures.empty()) h += "<ul class=\"failures\">\n" + failures + "</ul>\n";
    h += "<div class=\"cards\">\n";
    for (const std::string& c : g.configs) {
      const BenchRunResult* r = g.At(s, c);
      if (r == nullptr || r->status != kStatusOk) continue;
      h += "<div class=\"card\"><h3>" + HtmlEscape(c) + " &middot; " + StatusSpan(r->status) +
           "</h3>\n";
      if (r->status == kStatusOk && r->ate_rmse) {
        h += "<div class=\"small\">ATE " + Fixed(r->ate_rmse, 4) + " m &middot; RPE(1f) " +
             Fixed(r->rpe_trans, 4) + " m &middot; " + Fixed(r->ms_median, 1) + " ms median</div>";
      }
      if (!r->error.empty()) h += "<div class=\"err small\">" + HtmlEscape(r->error) + "</div>";
      for (const std::string* png : {&r->plot_trajectory, &r->plot_timing}) {
        if (exists(*png)) {
          h += "<img src=\"" + HtmlEscape(*png) + "\" alt=\"" + HtmlEscape(*png) + "\">\n";
        }
      }
      h += "<div class=\"small\">";
      for (const char* file : {"log.txt", "report.json", "trajectory.txt"}) {
        const std::string rel = r->run_dir + "/" + file;
        if (exists(rel)) h += "<a href=\"" + HtmlEscape(rel) + "\">" + file + "</a> ";
      }
      h += "</div></div>\n";
    }
    h += "</div>\n";
  }
  h += "</body></html>\n";
  return h;
}

// The per-sequence comparison charts; returns the relative paths drawn.
void DrawComparisons(const std::string& out_dir, const std::vector<BenchRunResult>& rows,
                     const std::map<std::string, RunSeries>& series,
                     std::map<std::string, std::string>* ate_pngs,
                     std::map<std::string, std::string>* time_pngs) {
  const Grid g = MakeGrid(rows);
  CreateDirectories(out_dir + "/plots");
  for (const std::string& s : g.sequences) {
    std::vector<ChartSeries> ate, time;
    for (const std::string& c : g.configs) {
      const BenchRunResult* r = g.At(s, c);
      if (r == nullptr || r->status != kStatusOk) continue;
      const auto it = series.find(r->run_dir);
      if (it == series.end()) continue;
      if (!it->second.ate_m.empty()) ate.push_back({c, it->second.distance_m, it->second.ate_m});
      if (!it->second.ms_total.empty()) {
        time.push_back({c, it->second.frame, it->second.ms_total});
      }
    }
    if (!ate.empty()) {
      LineChartOptions o;
      o.title = s + ": ATE along the path (aligned; se3 stereo, sim3 mono)";
      o.x_label = "distance travelled along the ground truth [m]";
      o.y_label = "ATE [m]";
      const std::string rel = "plots/" + s + "_ate.png";
      DrawLineChart(ate, o, out_dir + "/" + rel);
      (*ate_pngs)[s] = rel;
    }
    if (!time.empty()) {
      LineChartOptions o;
      o.title = s + ": per-frame time (total)";
      o.x_label = "frame";
      o.y_label = "time [ms]";
      const std::string rel = "plots/" + s + "_time.png";
      DrawLineChart(time, o, out_dir + "/" + rel);
      (*time_pngs)[s] = rel;
    }
  }
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
  WriteFileAtomically(out_dir + "/results.json",
                      [&](std::ostream& os) { os << j.dump(2) << "\n"; });
  WriteFileAtomically(out_dir + "/results.csv", [&](std::ostream& os) { os << ResultsCsv(rows); });
  WriteFileAtomically(out_dir + "/results.md",
                      [&](std::ostream& os) { os << Markdown(header, rows); });
  std::map<std::string, std::string> ate_pngs, time_pngs;
  DrawComparisons(out_dir, rows, series, &ate_pngs, &time_pngs);
  WriteFileAtomically(out_dir + "/report.html", [&](std::ostream& os) {
    os << Html(out_dir, header, rows, ate_pngs, time_pngs);
  });
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
