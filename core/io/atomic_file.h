#ifndef DALA_CORE_IO_ATOMIC_FILE_H_
#define DALA_CORE_IO_ATOMIC_FILE_H_

#include <functional>
#include <ostream>
#include <string>

namespace dala {

// Writes a file so that a reader never sees half of it: the content goes to "<path>.tmp.<pid>",
// is flushed and checked, then renamed over `path` (rename is atomic on POSIX). On any failure
// the temporary file is removed and dala::Error is thrown naming `path`.
//   WriteFileAtomically("traj.txt", [&](std::ostream& os) { os << ...; });
void WriteFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// Creates a directory and its parents; throws dala::Error naming the path when it cannot.
void CreateDirectories(const std::string& path);

}  // namespace dala

#endif  // DALA_CORE_IO_ATOMIC_FILE_H_
