// Fuzzes a EuRoC cam<N>/sensor.yaml (intrinsics, distortion, resolution, T_BS).
#include "core/io/euroc_dataset.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string path = dala::fuzz::WriteScratchFile("sensor.yaml", data, size);
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::ReadEurocSensorYaml(path); });
  return 0;
}
