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

}  // namespace thermodrift::svr_detail::simd

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define THERMODRIFT_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define THERMODRIFT_SIMD_CLONES
#endif
