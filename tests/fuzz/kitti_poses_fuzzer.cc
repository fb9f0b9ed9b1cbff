// Fuzzes a KITTI poses.txt (12 numbers per line) through ReadKittiSequence on a valid folder.
#include "core/io/kitti_dataset.h"
#include "tests/fuzz/fixtures.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string folder = dala::fuzz::KittiFolder();
  dala::fuzz::WriteScratchFile("kitti/poses.txt", data, size);
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::ReadKittiSequence(folder, {}); });
  return 0;
}
