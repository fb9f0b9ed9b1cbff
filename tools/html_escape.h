#ifndef DALA_TOOLS_HTML_ESCAPE_H_
#define DALA_TOOLS_HTML_ESCAPE_H_

#include <string>

namespace dala {

// `s` as HTML text or an attribute value in double quotes: & < > " replaced by their entities.
std::string EscapeHtml(const std::string& s);

}  // namespace dala

#endif  // DALA_TOOLS_HTML_ESCAPE_H_
