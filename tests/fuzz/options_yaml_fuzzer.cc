// Fuzzes the options YAML (`dala run --config`). An accepted file must also survive the round
// trip through `--dump-config`: the dumped YAML loads again to the same dump.
#include "backend/system_options.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string path = dala::fuzz::WriteScratchFile("options.yaml", data, size);
  dala::SystemOptions options;
  try {
    dala::LoadSystemOptions(path, &options);
  } catch (const dala::Error&) {
    return 0;  // Refused; other exceptions escape to libFuzzer as a finding.
  }
  const std::string dump = dala::SystemOptionsToYaml(options);
  dala::SystemOptions again;
  dala::LoadSystemOptions(dala::fuzz::WriteScratchFile("dumped.yaml", dump), &again);
  CHECK_EQ(dala::SystemOptionsToYaml(again), dump) << "the dumped options do not load back";
  return 0;
}
