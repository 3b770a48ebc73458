// Standard normal variates from std::mt19937_64, reproducible across standard libraries.
//
// Why not std::normal_distribution: the engine's output sequence is fixed by the C++
// standard, but the distributions' algorithms are not (libstdc++ and libc++ differ), so
// the same seed would give different noise on different machines. This is Marsaglia's
// polar form of the Box-Muller transform on the engine's raw 64-bit output: it needs only
// sqrt (correctly rounded by IEEE 754) and log, so results agree to the last bit wherever
// log does, and to an ulp otherwise.
#pragma once

#include <cstdint>
#include <random>

namespace thermodrift::sim {

class StandardNormal {
 public:
  explicit StandardNormal(std::uint64_t seed) : engine_(seed) {}

  double operator()();

 private:
  // Uniform on [0, 1) from the top 53 bits of one engine output.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// Seed of noise stream `stream` derived from the user's seed (SplitMix64), so that each
// axis and noise source has its own engine and changing one source leaves the others alone.
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream);

}  // namespace thermodrift::sim
