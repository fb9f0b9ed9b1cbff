#include "core/io/text_lines.h"

#include <cctype>
#include <charconv>
#include <cerrno>
#include <cstdint>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace dala {

std::vector<NumberedLine> ReadDataLines(const std::string& path, const std::string& what) {
  if (!std::filesystem::exists(path)) {
    throw Error() << "missing file '" << path << "' (" << what
                         << "): check the path or the dataset folder layout";
  }
  std::ifstream is(path);
  if (!is) throw Error() << "cannot read '" << path << "' (" << what << "): permission?";
  std::vector<NumberedLine> lines;
  std::string text;
  int number = 0;
  while (std::getline(is, text)) {
    ++number;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const size_t first = text.find_first_not_of(" \t");
    if (first == std::string::npos || text[first] == '#') continue;
    lines.push_back({number, text});
  }
  return lines;
}

std::vector<std::string> SplitFields(const std::string& s) {
  std::vector<std::string> fields;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == ',')) ++i;
    if (i >= s.size()) break;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != ',') ++j;
    fields.push_back(s.substr(i, j - i));
    i = j;
  }
  return fields;
}

int64_t ParseSecondsAsNs(const std::string& path, int line, const std::string& field) {
  const auto fail = [&]() {
    return Error() << path << ":" << line << ": '" << field << "' is not a time in seconds";
  };
  size_t i = 0;
  bool negative = false;
  if (i < field.size() && (field[i] == '+' || field[i] == '-')) negative = field[i++] == '-';
  std::string digits;
  int point = -1;  // Number of digits before the decimal point.
  for (; i < field.size() && (std::isdigit(static_cast<unsigned char>(field[i])) || field[i] == '.');
       ++i) {
    if (field[i] == '.') {
      if (point >= 0) throw fail();
      point = static_cast<int>(digits.size());
    } else {
      digits += field[i];
    }
  }
  if (digits.empty()) throw fail();
  if (point < 0) point = static_cast<int>(digits.size());
  int exponent = 0;
  if (i < field.size() && (field[i] == 'e' || field[i] == 'E')) {
    char* end = nullptr;
    const long e = std::strtol(field.c_str() + i + 1, &end, 10);
    if (end != field.c_str() + field.size() || e < -30 || e > 30) throw fail();
    exponent = static_cast<int>(e);
    i = field.size();
  }
  if (i != field.size()) throw fail();
  // value = 0.digits * 10^(point + exponent) seconds; ns keeps point + exponent + 9 digits.
  const int keep = point + exponent + 9;
  int64_t ns = 0;
  for (int k = 0; k < keep; ++k) {
    const int d = k < static_cast<int>(digits.size()) ? digits[k] - '0' : 0;
    if (ns > (INT64_MAX - d) / 10) throw fail();
    ns = ns * 10 + d;
  }
  if (keep >= 0 && keep < static_cast<int>(digits.size()) && digits[keep] >= '5') ++ns;
  return negative ? -ns : ns;
}

int64_t ParseInt64(const std::string& path, int line, const std::string& field) {
  int64_t value = 0;
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, value);
  if (ec != std::errc() || ptr != end) {
    throw Error() << path << ":" << line << ": '" << field
                  << "' is not an integer (expected nanoseconds)";
  }
  return value;
}

std::vector<double> ParseNumbers(const std::string& path, const NumberedLine& line) {
  std::vector<double> values;
  for (const std::string& field : SplitFields(line.text)) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(field.c_str(), &end);
    if (end != field.c_str() + field.size() || errno == ERANGE || !std::isfinite(v)) {
      throw Error() << path << ":" << line.number << ": '" << field
                           << "' is not a finite number";
    }
    values.push_back(v);
  }
  return values;
}

}  // namespace dala
