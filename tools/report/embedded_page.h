#ifndef DALA_TOOLS_REPORT_EMBEDDED_PAGE_H_
#define DALA_TOOLS_REPORT_EMBEDDED_PAGE_H_

// The scripts and style that report.html carries inline, so that it opens from disk with no
// server and no network. Their text is compiled in from the files (tools/CMakeLists.txt,
// cmake/embed_text_files.cmake).

#include <string>

namespace dala::report {

const std::string& ThreeJs();          // third_party/three/three.min.js (three.js r147, MIT)
const std::string& OrbitControlsJs();  // third_party/three/OrbitControls.js (THREE.OrbitControls)
const std::string& ReportPageJs();     // tools/report/page/report.js: the page's viewer and charts
const std::string& ReportPageCss();    // tools/report/page/report.css

}  // namespace dala::report

#endif  // DALA_TOOLS_REPORT_EMBEDDED_PAGE_H_
