// Fuzzes a EuRoC mav0/cam0/data.csv ("t_ns,filename") through ReadEurocSequence (monocular).
#include "core/io/euroc_dataset.h"
#include "tests/fuzz/fixtures.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string folder = dala::fuzz::EurocFolder();
  dala::fuzz::WriteScratchFile("euroc/mav0/cam0/data.csv", data, size);
  dala::DatasetOptions options;
  options.allow_missing_images = size > 0 && (data[0] & 1);
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::ReadEurocSequence(folder, options); });
  return 0;
}
