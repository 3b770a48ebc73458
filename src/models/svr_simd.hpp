// Internal to the ε-SVR solver: four-lane double vectors (GCC vector extensions) for the
// loops that run over every active sample, compiled twice — AVX2 and baseline x86-64 —
// with the variant chosen at load time (target_clones). The binary runs on any x86-64.
// No FMA in either variant, so both give bit-identical results.
#pragma once

#include <cstring>

// GCC warns that these types change the ABI of non-AVX functions; they never cross one.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace thermodrift::svr_detail::simd {

typedef double Lanes __attribute__((vector_size(32)));
typedef long long LaneMask __attribute__((vector_size(32)));
constexpr int kLanes = 4;

inline Lanes load(const double* from) {
  Lanes lanes;
  std::memcpy(&lanes, from, sizeof lanes);
  return lanes;
}
inline void store(double* to, Lanes lanes) { std::memcpy(to, &lanes, sizeof lanes); }
inline Lanes broadcast(double value) { return Lanes{value, value, value, value}; }

// exp(-gamma · squared) for squared ≥ 0, lane-wise: exp(x) = 2^k exp(x - k ln 2) with
// k = round(x / ln 2) and a degree-13 Taylor polynomial on |x - k ln 2| ≤ ln2/2
// (truncation below 1e-17 relative; measured ≤ 2.3e-16 relative to libm's exp).
__attribute__((always_inline)) inline Lanes negative_exp_lanes(Lanes squared, Lanes factor) {
  const Lanes round_magic = broadcast(6755399441055744.0);  // 1.5·2^52: adding it rounds to an integer
  const Lanes x = squared * factor;
  const Lanes k = (x * 1.4426950408889634 + round_magic) - round_magic;
  const Lanes r = (x - k * 6.93145751953125e-1) - k * 1.42860682030941723212e-6;  // ln 2 in two parts
  Lanes p = broadcast(1.0 / 6227020800.0);  // 1/13!
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // 2^k from the integer in the low mantissa bits of k + 1023 + 1.5·2^52 (k ≥ -1022 here)
  const LaneMask exponent = (LaneMask)(k + (round_magic + 1023.0)) << 52;
  const Lanes result = p * (Lanes)exponent;
  return x < broadcast(-708.0) ? broadcast(0.0) : result;
}

}  // namespace thermodrift::svr_detail::simd

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define THERMODRIFT_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define THERMODRIFT_SIMD_CLONES
#endif
