// Fuzzes the map loader (System::LoadMap, core/io/map_file.cc): a .dmap from a stranger must be
// refused with dala::Error, never crash or allocate without bound (-rss_limit_mb catches that).
// Each input is read twice: as is (mostly refused by the checksum), and with its trailing FNV-1a
// hash recomputed, so that the fuzzer reaches the parser behind the checksum.
#include <cstring>

#include "backend/system.h"
#include "tests/fuzz/fuzz_util.h"

namespace {
uint64_t Fnv1a(const uint8_t* data, size_t n) {  // As map_file.cc computes it.
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= data[i];
    h *= 0x100000001b3ull;
  }
  return h;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string raw = dala::fuzz::WriteScratchFile("raw.dmap", data, size);
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::System::LoadMap(raw); });
  if (size < 8) return 0;
  std::string bytes(reinterpret_cast<const char*>(data), size);
  const uint64_t hash = Fnv1a(data, size - 8);
  std::memcpy(&bytes[size - 8], &hash, sizeof(hash));
  const std::string hashed = dala::fuzz::WriteScratchFile("hashed.dmap", bytes);
  dala::fuzz::ExpectOnlyDalaErrors([&] { dala::System::LoadMap(hashed); });
  return 0;
}
