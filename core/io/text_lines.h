#ifndef DALA_CORE_IO_TEXT_LINES_H_
#define DALA_CORE_IO_TEXT_LINES_H_

#include <cstdint>
#include <string>
#include <vector>

namespace dala {

// A data line of a text file with its 1-based line number (for error messages).
struct NumberedLine {
  int number = 0;
  std::string text;
};

// Reads the non-empty lines of a text file that do not start with '#' (after leading blanks).
// Throws dala::Error when the file cannot be opened, with `what` saying what it should be
// (e.g. "the KITTI ground truth poses").
std::vector<NumberedLine> ReadDataLines(const std::string& path, const std::string& what);

// Splits on blanks and/or commas and parses every field as a double. Throws dala::Error naming
// path:line and the bad field when a field is not a number.
std::vector<double> ParseNumbers(const std::string& path, const NumberedLine& line);

// Splits a line on blanks and/or commas.
std::vector<std::string> SplitFields(const std::string& text);

// Parses a time in seconds written in decimal or scientific notation ("1403715572.212143183",
// "1.403715572212143183e+09") into nanoseconds exactly, without going through a double (which
// keeps only ~16 digits, too few for epoch times in ns). Rounds to the nearest ns. Throws
// dala::Error naming path:line when the field is not a number.
int64_t ParseSecondsAsNs(const std::string& path, int line, const std::string& field);

// Parses a whole decimal integer exactly (e.g. EuRoC nanosecond stamps); dala::Error naming
// path:line otherwise.
int64_t ParseInt64(const std::string& path, int line, const std::string& field);

}  // namespace dala

#endif  // DALA_CORE_IO_TEXT_LINES_H_
