#include "core/yaml_single_document.h"

#include <cstddef>
#include <string>

#include "core/error.h"

namespace dala {
namespace {

// True when line[from..] holds nothing but blanks and an optional comment.
bool NothingFrom(const std::string& line, size_t from) {
  const size_t k = line.find_first_not_of(' ', from);
  return k == std::string::npos || line[k] == '#';
}

}  // namespace

void CheckSingleYamlDocument(const std::string& yaml, const std::string& name) {
  auto refuse = [&name](int line_number, const std::string& why) {
    throw Error() << name << ": line " << line_number << ": " << why
                  << "; dala reads one YAML document per file (OpenCV's parser cannot read on "
                     "past it): fix the indentation or remove the text";
  };
  enum class State { kBeforeRoot, kBlockRoot, kEnded };
  State state = State::kBeforeRoot;
  size_t root_indent = 0;
  int root_line = 0;
  int end_line = 0;  // The line of the "..." or "---" that ended the document.
  int line_number = 0;
  size_t begin = 0;
  while (begin <= yaml.size()) {
    size_t end = yaml.find('\n', begin);
    if (end == std::string::npos) end = yaml.size();
    std::string line = yaml.substr(begin, end - begin);
    begin = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    size_t col = line.find_first_not_of(' ');
    if (col == std::string::npos || line[col] == '#') continue;  // Blank or comment.

    switch (state) {
      case State::kBeforeRoot: {
        if (line[col] == '%') continue;  // A directive such as "%YAML:1.0".
        if (line.compare(col, 3, "---") == 0) {
          col = line.find_first_not_of(' ', col + 3);
          if (col == std::string::npos || line[col] == '#') continue;
        }
        // A flow root ('{' or '[') is refused by OpenCV's parser itself, without a hang.
        root_indent = col;
        root_line = line_number;
        state = State::kBlockRoot;
        break;
      }
      case State::kBlockRoot: {
        if (col < root_indent) {
          refuse(line_number, "indented by " + std::to_string(col) + " where the document (line " +
                                  std::to_string(root_line) + ") is indented by " +
                                  std::to_string(root_indent) + ", which ends it");
        }
        if (line.compare(col, 3, "...") == 0 || line.compare(col, 3, "---") == 0) {
          if (!NothingFrom(line, col + 3)) refuse(line_number, "text after a document marker");
          state = State::kEnded;
          end_line = line_number;
        }
        break;
      }
      case State::kEnded:
        refuse(line_number,
               "text after the end of the document on line " + std::to_string(end_line));
    }
  }
}

}  // namespace dala
