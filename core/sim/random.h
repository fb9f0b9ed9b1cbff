#ifndef DALA_CORE_SIM_RANDOM_H_
#define DALA_CORE_SIM_RANDOM_H_

#include <cstdint>
#include <random>

namespace dala::sim {

// A seeded random source whose output is the same on every platform: std::mt19937_64 is
// specified bit-exactly, and the conversion to doubles is ours (the std distributions are not
// specified bit-exactly).
class SimRng {
 public:
  explicit SimRng(uint64_t seed) : engine_(seed) {}
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }
  double Uniform(double a, double b) { return a + (b - a) * Uniform(); }
  // Uniform integer in [a, b].
  int Int(int a, int b) { return a + static_cast<int>(Uniform() * (b - a + 1)); }
  uint64_t Bits() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

// Mixes a seed with stream indices into a new seed (splitmix64 finaliser).
inline uint64_t MixSeed(uint64_t seed, uint64_t a, uint64_t b = 0) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (a + 1) + 0xBF58476D1CE4E5B9ull * (b + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_RANDOM_H_
