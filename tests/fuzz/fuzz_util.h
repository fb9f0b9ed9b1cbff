#ifndef DALA_TESTS_FUZZ_FUZZ_UTIL_H_
#define DALA_TESTS_FUZZ_FUZZ_UTIL_H_

// Shared by the libFuzzer targets in this folder (built with -DDALA_FUZZ=ON; tests/fuzz/README.md).
//
// dala's readers take paths, so each target writes the input to a scratch file and calls the
// reader as `dala run` would. A reader may refuse an input only with dala::Error (whose message
// names the file and the fix); anything else that leaves it is a finding: another exception
// (std::out_of_range, std::length_error, cv::Exception) aborts here, and a sanitizer report or a
// crash is caught by libFuzzer itself.

#include <glog/logging.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace dala::fuzz {

// A scratch folder per process (libFuzzer's -fork/-jobs run several), removed at exit.
class ScratchDir {
 public:
  static const std::string& Path() {
    static ScratchDir dir;
    return dir.path_;
  }

 private:
  ScratchDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string tmpl = std::string(tmp && *tmp ? tmp : "/tmp") + "/dala_fuzz_XXXXXX";
    CHECK(mkdtemp(tmpl.data()) != nullptr) << "cannot create a scratch folder " << tmpl;
    path_ = tmpl;
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::string path_;
};

inline std::string WriteScratchFile(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = ScratchDir::Path() + "/" + name;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream os(path, std::ios::binary | std::ios::trunc);
  os.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  CHECK(os.good()) << "cannot write " << path;
  return path;
}

inline std::string WriteScratchFile(const std::string& name, const std::string& text) {
  return WriteScratchFile(name, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// Runs `read`; a dala::Error with a message is the accepted way to refuse the input.
template <typename Read>
void ExpectOnlyDalaErrors(Read&& read) {
  try {
    read();
  } catch (const Error& e) {
    // An empty message would tell the user nothing: a finding too.
    if (e.message().empty()) {
      std::fprintf(stderr, "dala::Error with an empty message\n");
      std::abort();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "exception other than dala::Error escaped the reader: %s\n", e.what());
    std::abort();
  }
}

// Quiet glog: the readers' warnings would flood the fuzzer's output.
inline void QuietLogging() {
  static bool done = false;
  if (done) return;
  done = true;
  google::InitGoogleLogging("dala_fuzz");
  FLAGS_minloglevel = 3;
}

}  // namespace dala::fuzz

#endif  // DALA_TESTS_FUZZ_FUZZ_UTIL_H_
