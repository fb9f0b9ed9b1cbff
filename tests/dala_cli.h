#ifndef DALA_TESTS_DALA_CLI_H_
#define DALA_TESTS_DALA_CLI_H_

// The dala command-line tool run from a test: DALA_BINARY, which tests/CMakeLists.txt defines
// for the test targets that run it.

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/test_util.h"

namespace dala::testing {

struct DalaCliResult {
  int status = -1;   // the exit code; -1 when the tool did not exit normally (a signal)
  std::string out;   // what it printed on stdout
  std::string err;   // ... and on stderr
  std::string log() const { return out + err; }
};

// Runs `dala ARGS` through the shell (ARGS may hold quotes and `cd`-free redirections of its
// own), its stdout and stderr kept in LOG_PREFIX.out and LOG_PREFIX.err as well as returned.
inline DalaCliResult RunDala(const std::string& args, const std::string& log_prefix) {
  const std::string out = log_prefix + ".out";
  const std::string err = log_prefix + ".err";
  const std::string cmd = std::string(DALA_BINARY) + " " + args + " > " + out + " 2> " + err;
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadAll(out), ReadAll(err)};
}

// Runs `dala ARGS` whose results go into the folder OUT (`run DATA ... --out OUT`; its logs are
// OUT.out and OUT.err) and returns OUT/report.json parsed. A non-zero exit or a missing or
// unreadable report is a test failure; the result is then discarded (is_discarded()).
inline nlohmann::json RunDalaForReport(const std::string& args, const std::string& out) {
  const DalaCliResult r = RunDala(args, out);
  EXPECT_EQ(r.status, 0) << r.log();
  std::ifstream in(out + "/report.json");
  const nlohmann::json report = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  EXPECT_FALSE(report.is_discarded()) << "no readable report.json in " << out;
  return report;
}

}  // namespace dala::testing

#endif  // DALA_TESTS_DALA_CLI_H_
