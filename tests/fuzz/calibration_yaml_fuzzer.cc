// Fuzzes the calibration override YAML (--calibration / DatasetOptions::calibration_yaml).
#include "core/io/calibration_yaml.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string path = dala::fuzz::WriteScratchFile("calibration.yaml", data, size);
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::ReadCalibrationYaml(path); });
  return 0;
}
