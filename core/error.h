#ifndef DALA_CORE_ERROR_H_
#define DALA_CORE_ERROR_H_

#include <exception>
#include <sstream>
#include <string>

namespace dala {

// A user or environment error at the I/O boundary: a missing or malformed file, a bad
// calibration, an invalid option. The message names the file (and line) or the option, says what
// is wrong and how to fix it. The CLI prints it and exits with status 2. Inside the pipeline,
// data that allows no answer is a returned status, never an Error (see DESIGN.md).
//
// The message can be built with stream syntax:
//   throw dala::Error() << path << ":" << line << ": expected 12 numbers, got " << n;
class Error : public std::exception {
 public:
  Error() = default;
  explicit Error(std::string message) : message_(std::move(message)) {}

  template <typename T>
  Error& operator<<(const T& value) {
    std::ostringstream os;
    os << value;
    message_ += os.str();
    return *this;
  }

  const char* what() const noexcept override { return message_.c_str(); }
  const std::string& message() const { return message_; }

 private:
  std::string message_;
};

}  // namespace dala

#endif  // DALA_CORE_ERROR_H_
