#include "tools/stop_signal.h"

#include <glog/logging.h>
#include <unistd.h>

#include <atomic>

namespace dala {
namespace {

// Lock-free, so usable in a signal handler, and visible across threads (the signal may be
// delivered to a worker thread).
std::atomic<int> g_received{0};
static_assert(std::atomic<int>::is_always_lock_free);

// Async-signal-safe: an atomic flag and write(2) only.
// The first signal wins (compare-exchange: two signals delivered to two threads at once cannot
// both count as the first).
extern "C" void OnStopSignal(int signal) {
  int none = 0;
  if (!g_received.compare_exchange_strong(none, signal)) {
    static const char kBusy[] = "\n[stop] already stopping: the results are being written\n";
    const ssize_t ignored = write(STDERR_FILENO, kBusy, sizeof(kBusy) - 1);
    (void)ignored;
  }
}

}  // namespace

StopSignal::StopSignal() {
  g_received = 0;
  struct sigaction action = {};
  action.sa_handler = &OnStopSignal;
  sigemptyset(&action.sa_mask);
  // SA_RESTART: a read in progress (an image file) goes on instead of failing with EINTR, which
  // would look like a corrupt image.
  action.sa_flags = SA_RESTART;
  PCHECK(sigaction(SIGINT, nullptr, &previous_int_) == 0);
  // A process started with SIGINT ignored (nohup, a background job of a script) keeps ignoring
  // it, as shells intend; SIGTERM is always a stop request.
  if (previous_int_.sa_handler != SIG_IGN) {
    PCHECK(sigaction(SIGINT, &action, nullptr) == 0) << "installing the SIGINT handler";
  }
  PCHECK(sigaction(SIGTERM, &action, &previous_term_) == 0) << "installing the SIGTERM handler";
}

StopSignal::~StopSignal() {
  sigaction(SIGINT, &previous_int_, nullptr);
  sigaction(SIGTERM, &previous_term_, nullptr);
}

int StopSignal::received() const { return g_received; }

const char* StopSignalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
  }
  return "a signal";
}

}  // namespace dala
