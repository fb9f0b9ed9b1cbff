#ifndef DALA_TOOLS_REPORT_RUN_FOLDER_H_
#define DALA_TOOLS_REPORT_RUN_FOLDER_H_

// The report's input read back from files (`dala view`): an earlier run's output folder, or a
// saved map alone.

#include <string>

#include "tools/report/report_data.h"

namespace dala::report {

// A `dala run` output folder: trajectory.txt, report.json (frames, summary, the printed summary,
// the dataset's path (absolute_path when present) and format, the mode) and map.dmap's landmarks. The ground truth comes from
// the dataset named in report.json, opened again with its format, and is evaluated as `dala run`
// does (SE(3), Sim(3) for mono); when the dataset cannot be opened (moved, or it needs
// --calibration), the report goes without ground truth and `*note` says why (empty otherwise).
// Throws dala::Error naming the file that is missing or malformed and what to do.
ReportInput ReportInputFromRunFolder(const std::string& dir, std::string* note);

// A saved map (map.dmap of a run): its landmarks and its keyframes; no path, no charts.
// Throws dala::Error when the file is not a readable map (core/io/map_file.h).
ReportInput ReportInputFromMapFile(const std::string& path);

}  // namespace dala::report

#endif  // DALA_TOOLS_REPORT_RUN_FOLDER_H_
