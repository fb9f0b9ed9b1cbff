#include "tools/process_memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace dala {

double ResidentMemoryMb() {
  // statm: total program size, then resident pages.
  std::ifstream statm("/proc/self/statm");
  long total = 0, resident = 0;
  if (!(statm >> total >> resident)) return 0.0;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

double PeakResidentMemoryMb() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB.
}

}  // namespace dala
