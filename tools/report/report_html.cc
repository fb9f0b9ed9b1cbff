#include "tools/report/report_html.h"

#include "core/io/atomic_file.h"
#include "tools/html_escape.h"
#include "tools/report/embedded_page.h"

namespace dala::report {
namespace {

// JSON inside a <script> element: "</" would end the element, so it is written "<\/" (the
// same string in JSON; "</" can only occur inside a string there).
std::string ScriptSafeJson(const nlohmann::json& data) {
  std::string text =
      data.dump(-1, ' ', /*ensure_ascii=*/false, nlohmann::json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size() + 16);
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') {
      out += "<\\/";
      ++i;
    } else {
      out += text[i];
    }
  }
  return out;
}


}  // namespace

std::string ReportHtml(const nlohmann::json& data) {
  const std::string title = "dala: " + data.value("title", std::string("run"));
  std::string html;
  html.reserve(ThreeJs().size() + OrbitControlsJs().size() + ReportPageJs().size() + (1 << 20));
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>";
  html += EscapeHtml(title);
  html += "</title>\n<style>\n";
  html += ReportPageCss();
  html += "</style>\n</head>\n<body>\n<div id=\"app\"></div>\n";
  // three.js r147 (MIT, third_party/three/LICENSE) and its OrbitControls, as published on npm.
  html += "<script>\n";
  html += ThreeJs();
  html += "\n</script>\n<script>\n";
  html += OrbitControlsJs();
  html += "\n</script>\n<script id=\"dala-data\" type=\"application/json\">";
  html += ScriptSafeJson(data);
  html += "</script>\n<script>\n";
  html += ReportPageJs();
  html += "\n</script>\n</body>\n</html>\n";
  return html;
}

void WriteReportHtml(const std::string& path, const nlohmann::json& data) {
  const std::string html = ReportHtml(data);
  WriteFileAtomically(path, [&](std::ostream& os) { os.write(html.data(), html.size()); });
}

}  // namespace dala::report
