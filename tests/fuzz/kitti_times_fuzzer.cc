// Fuzzes a KITTI times.txt through ReadKittiSequence on a valid stereo folder (two images).
#include "core/io/kitti_dataset.h"
#include "tests/fuzz/fixtures.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string folder = dala::fuzz::KittiFolder();
  dala::fuzz::WriteScratchFile("kitti/times.txt", data, size);
  dala::DatasetOptions options;
  options.allow_missing_images = size > 0 && (data[0] & 1);  // Both paths of the image check.
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::ReadKittiSequence(folder, options); });
  return 0;
}
