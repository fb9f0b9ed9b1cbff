// Fuzzes a `dala bench` suite YAML. The suite sits in a folder that holds a sequence folder
// `seq/` and a config file `kitti.yaml`, so that valid entries can name them.
#include "tests/fuzz/fuzz_util.h"
#include "tools/bench/suite.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  static const bool folders = [] {
    std::filesystem::create_directories(dala::fuzz::ScratchDir::Path() + "/bench/seq");
    dala::fuzz::WriteScratchFile("bench/kitti.yaml", "ba:\n  window_size: 5\n");
    return true;
  }();
  (void)folders;
  const std::string path = dala::fuzz::WriteScratchFile("bench/suite.yaml", data, size);
  dala::fuzz::ExpectOnlyDalaErrors([&] {
    const dala::bench::BenchSuite suite = dala::bench::LoadBenchSuite(path);
    dala::bench::MakeRunList(suite);
  });
  return 0;
}
