#include "core/io/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "core/error.h"

namespace dala {

void WriteFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  try {
    std::ofstream os(tmp, std::ios::out | std::ios::trunc | std::ios::binary);
    if (!os) {
      throw Error() << "cannot open '" << tmp
                           << "' for writing: check that the folder exists and is writable";
    }
    write(os);
    os.flush();
    if (!os) throw Error() << "failed while writing '" << tmp << "' (disk full?)";
    os.close();
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
      throw Error() << "cannot rename '" << tmp << "' to '" << path << "': " << ec.message();
    }
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
}

void CreateDirectories(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec || !std::filesystem::is_directory(path)) {
    throw Error() << "cannot create the output folder '" << path << "': "
                         << (ec ? ec.message() : "a file of that name exists")
                         << "; choose another path with --out";
  }
}

}  // namespace dala
