#ifndef DALA_TOOLS_REPORT_REPORT_HTML_H_
#define DALA_TOOLS_REPORT_REPORT_HTML_H_

// report.html: one self-contained page that shows a run, opened from disk with no server and no
// network. It carries inline three.js (third_party/three), the page's script and style
// (tools/report/page) and the run's data (ReportDataJson): a 3D view (map points coloured by
// height, keyframe frusta, estimated path, ground truth, loop edges, lost and relocalised
// frames; orbit / pan / zoom, top and side views), a time slider that moves a camera marker
// along the path (the URL's #t=0.5 sets it: fraction of the run's time), per-frame charts and
// the printed summary. The page writes its state into document.title ("dala report: ready",
// "dala report: error: ..."), which a headless browser can read.

#include <nlohmann/json.hpp>
#include <string>

namespace dala::report {

// The page's text for `data` (ReportDataJson).
std::string ReportHtml(const nlohmann::json& data);

// Writes ReportHtml(data) to `path` atomically (temporary file, then rename). Throws dala::Error
// naming the file when it cannot be written.
void WriteReportHtml(const std::string& path, const nlohmann::json& data);

}  // namespace dala::report

#endif  // DALA_TOOLS_REPORT_REPORT_HTML_H_
