// `dala view OUT_DIR | MAP.dmap`: writes the report.html of an earlier run (or of a saved map)
// again from its files, without running anything, and says where it is.
#include <gflags/gflags.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "core/error.h"
#include "tools/command.h"
#include "tools/report/report_data.h"
#include "tools/report/report_html.h"
#include "tools/report/run_folder.h"

DEFINE_bool(open, false, "view: open the written report with xdg-open (a desktop's browser)");

namespace dala {
namespace {

// The path in single quotes for /bin/sh.
std::string ShellQuoted(const std::string& s) {
  std::string out = "'";
  for (const char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

int RunView(const std::vector<std::string>& args) {
  if (args.size() != 1) {
    throw Error() << "expected one run folder (the --out of `dala run`) or map file, got "
                  << args.size() << " arguments; usage: dala view OUT_DIR | MAP.dmap [--open]";
  }
  const std::filesystem::path target(args[0]);
  if (!std::filesystem::exists(target)) {
    throw Error() << args[0] << ": does not exist; give the --out folder of a `dala run` or a "
                  << "map.dmap file";
  }
  report::ReportInput input;
  std::string html_path;
  if (std::filesystem::is_directory(target)) {
    std::string note;
    input = report::ReportInputFromRunFolder(args[0], &note);
    if (!note.empty()) std::cerr << "[view] " << note << "\n";
    html_path = (target / "report.html").string();
  } else {
    input = report::ReportInputFromMapFile(args[0]);
    // Beside the map, not over the run's own report.html: map.dmap -> map_report.html.
    html_path = (target.parent_path() / (target.stem().string() + "_report.html")).string();
  }
  report::WriteReportHtml(html_path, report::ReportDataJson(input));
  std::cout << html_path << "\n";
  if (FLAGS_open) {
    const std::string command = "xdg-open " + ShellQuoted(html_path) + " >/dev/null 2>&1";
    if (std::system(command.c_str()) != 0) {
      std::cerr << "[view] xdg-open could not open it (no desktop?): open " << html_path
                << " in a browser\n";
    }
  }
  return 0;
}

const CommandRegistrar kRegistrar(
    {"view", "write the 3D report (report.html) of an earlier run or of a saved map",
     "dala view OUT_DIR [--open]\n"
     "       dala view MAP.dmap [--open]\n\n"
     "Writes report.html again from the files `dala run` left in OUT_DIR (trajectory.txt,\n"
     "report.json, map.dmap; the ground truth from the dataset report.json names, when it can\n"
     "still be opened) and prints its path. For a saved map alone (MAP.dmap), writes\n"
     "MAP_report.html beside it: its landmarks and keyframes. The page opens from disk in any\n"
     "browser with WebGL (docs/pipeline.md, \"The report\"); --open hands it to xdg-open.",
     &RunView, __FILE__});

}  // namespace
}  // namespace dala
