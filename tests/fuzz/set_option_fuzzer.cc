// Fuzzes `--set section.key=value` strings: each input line is one assignment, applied in turn.
#include <sstream>

#include "backend/system_options.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  std::istringstream lines(std::string(reinterpret_cast<const char*>(data), size));
  dala::SystemOptions options;
  std::string line;
  while (std::getline(lines, line)) {
    dala::fuzz::ExpectOnlyDalaErrors([&] { dala::SetSystemOption(line, &options); });
  }
  return 0;
}
