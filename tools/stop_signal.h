#ifndef DALA_TOOLS_STOP_SIGNAL_H_
#define DALA_TOOLS_STOP_SIGNAL_H_

// Ctrl-C (SIGINT) and SIGTERM as a request to stop: while a StopSignal lives, those signals only
// set a flag that a long loop checks between steps (`dala run` between frames), so the command
// can finish its outputs for the work done instead of dying half way. A second signal is not a
// second request: it prints that the results are being written (SIGKILL still ends the process).
//
//   StopSignal stop;
//   while (!stop.received() && MoreWork()) DoOneStep();
//   if (stop.received()) ...  // exit with 128 + stop.received(), as a shell expects.
//
// One StopSignal at a time per process; the destructor restores the previous handlers.

#include <csignal>

namespace dala {

class StopSignal {
 public:
  StopSignal();
  ~StopSignal();
  StopSignal(const StopSignal&) = delete;
  StopSignal& operator=(const StopSignal&) = delete;

  // The first stop signal received (SIGINT or SIGTERM), or 0.
  int received() const;

 private:
  struct sigaction previous_int_ = {};
  struct sigaction previous_term_ = {};
};

// "SIGINT", "SIGTERM", or "a signal".
const char* StopSignalName(int signal);

}  // namespace dala

#endif  // DALA_TOOLS_STOP_SIGNAL_H_
