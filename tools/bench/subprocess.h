#ifndef DALA_TOOLS_BENCH_SUBPROCESS_H_
#define DALA_TOOLS_BENCH_SUBPROCESS_H_

// Running a command as a child process, for crash isolation: a child that fails, crashes or
// hangs is reported, never takes the caller down. Thread-safe (each call waits for its own pid),
// so several threads can each run one child.

#include <string>
#include <vector>

namespace dala::bench {

struct SubprocessOptions {
  // File that receives the child's stdout and stderr (created or truncated).
  std::string log_path;
  // Kill the child (SIGKILL) after this many seconds of wall time; 0 = never.
  double timeout_s = 0.0;
};

struct SubprocessResult {
  bool started = false;  // False when fork/exec failed: see error.
  bool exited = false;   // Exited normally: exit_code is valid.
  int exit_code = -1;
  bool signaled = false;  // Killed by a signal: signal is valid.
  int signal = 0;
  bool timed_out = false;  // Killed by us after the timeout (then also signaled).
  double wall_s = 0.0;
  double peak_rss_mb = 0.0;  // The child's ru_maxrss (wait4), MiB.
  std::string error;         // Why it did not start.
};

// Runs argv[0] (a path, not searched in PATH) with the arguments argv[1..] and waits for it.
SubprocessResult RunSubprocess(const std::vector<std::string>& argv,
                               const SubprocessOptions& options);

// The command as one shell-quoted line (logs, results.json).
std::string ShellJoin(const std::vector<std::string>& argv);

// The last `max_lines` non-empty lines of a text file (at most `max_chars`), for error messages.
std::string TailOfFile(const std::string& path, int max_lines = 6, size_t max_chars = 800);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_SUBPROCESS_H_
