#ifndef DALA_TOOLS_PROCESS_MEMORY_H_
#define DALA_TOOLS_PROCESS_MEMORY_H_

// The memory this process uses, for the run report's memory curve (dala run: resident memory
// per frame, memory.png) and its peak.

namespace dala {

// Resident set size now, MiB (Linux /proc/self/statm; 0 where it cannot be read).
double ResidentMemoryMb();
// Peak resident set size of the process so far, MiB (getrusage ru_maxrss; 0 if unavailable).
double PeakResidentMemoryMb();

}  // namespace dala

#endif  // DALA_TOOLS_PROCESS_MEMORY_H_
