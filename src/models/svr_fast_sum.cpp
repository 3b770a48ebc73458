// The field's RBF sum (svr_kernel.hpp, rbf_sum_fast): the decision function evaluated with
// the widest arithmetic the CPU has. This file is compiled with -ffp-contract=fast
// (src/CMakeLists.txt), so that a·b + c becomes one fused multiply-add in the variants
// built for FMA; fits never call it (their sums must give the same bits on every x86-64).
#include "svr_kernel.hpp"
#include "svr_simd.hpp"

#include <cstring>

namespace thermodrift::svr_detail {

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
namespace {

typedef double Lanes8 __attribute__((vector_size(64)));
typedef long long Mask8 __attribute__((vector_size(64)));
using Lanes4 = simd::Lanes;

template <typename Lanes>
__attribute__((always_inline)) inline Lanes splat(double value) {
  return Lanes{} + value;
}

template <typename Lanes>
__attribute__((always_inline)) inline Lanes load(const double* from) {
  Lanes lanes;
  std::memcpy(&lanes, from, sizeof lanes);
  return lanes;
}

constexpr double kRoundMagic = 6755399441055744.0;  // 1.5·2^52: adding it rounds to an integer

// exp(x) for x ≤ 0, eight lanes: x = (16m + j)·ln2/16 + r with |r| ≤ ln2/32, so
// exp(x) = 2^m · 2^(j/16) · exp(r); 2^(j/16) from a 16-entry table held in two
// registers (one permute, no memory gather), exp(r) − 1 by a degree-7 Taylor polynomial
// (truncation below 2e-18 relative).
__attribute__((always_inline)) inline Lanes8 exp_table16(Lanes8 x) {
  alignas(64) static constexpr double kTable[16] = {
      0x1.0000000000000p+0, 0x1.0b5586cf9890fp+0, 0x1.172b83c7d517bp+0, 0x1.2387a6e756238p+0,
      0x1.306fe0a31b715p+0, 0x1.3dea64c123422p+0, 0x1.4bfdad5362a27p+0, 0x1.5ab07dd485429p+0,
      0x1.6a09e667f3bcdp+0, 0x1.7a11473eb0187p+0, 0x1.8ace5422aa0dbp+0, 0x1.9c49182a3f090p+0,
      0x1.ae89f995ad3adp+0, 0x1.c199bdd85529cp+0, 0x1.d5818dcfba487p+0, 0x1.ea4afa2a490dap+0};
  const Lanes8 shifted = x * 0x1.71547652b82fep+4 + kRoundMagic;  // 16/ln2
  const Lanes8 k = shifted - kRoundMagic;
  // ln2/16 in two parts; the first has 21 significant bits, so k times it is exact.
  const Lanes8 r = (x - k * 0x1.62e42p-5) - k * 0x1.fdf473de6af28p-26;
  Lanes8 p = splat<Lanes8>(1.0 / 5040);
  p = p * r + 1.0 / 720;
  p = p * r + 1.0 / 120;
  p = p * r + 1.0 / 24;
  p = p * r + 1.0 / 6;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r;  // exp(r) − 1
  // The low mantissa bits of `shifted` hold k in two's complement: j = k mod 16, and
  // (k − j)/16 = m goes into the exponent field of the table's entry (m ≥ −1022 here).
  const Mask8 bits = (Mask8)shifted;
  const Mask8 j = bits & 15;
  const Lanes8 low = load<Lanes8>(kTable), high = load<Lanes8>(kTable + 8);
  const Lanes8 scaled = (Lanes8)((Mask8)__builtin_shuffle(low, high, j) + ((bits - j) << 48));
  const Lanes8 result = scaled + scaled * p;
  return x < -708.0 ? splat<Lanes8>(0.0) : result;
}

// exp(−γ·squared) in lanes: on eight, exp_table16; on four, the solver's reduction and
// degree-13 polynomial (svr_simd.hpp), here with fused multiply-adds.
template <typename Lanes>
__attribute__((always_inline)) inline Lanes exp_lanes(Lanes squared, Lanes factor) {
  if constexpr (sizeof(Lanes) == sizeof(Lanes8)) {
    return exp_table16(squared * factor);
  } else {
    return simd::negative_exp_lanes(squared, factor);
  }
}

// Σ_f (columns[f][k + i] − x[f])² in lane i, for lanes i < rest; the others read x (distance 0).
template <typename Lanes>
__attribute__((always_inline)) inline Lanes squared_distance(const double* const* columns, std::size_t feature_count,
                                                             const double* x, std::size_t k, std::size_t rest) {
  constexpr std::size_t width = sizeof(Lanes) / sizeof(double);
  Lanes sum = splat<Lanes>(0.0);
  for (std::size_t f = 0; f < feature_count; ++f) {
    Lanes values;
    if (rest == width) {
      values = load<Lanes>(columns[f] + k);
    } else {
      double padded[width];
      for (std::size_t i = 0; i < width; ++i) padded[i] = i < rest ? columns[f][k + i] : x[f];
      values = load<Lanes>(padded);
    }
    const Lanes difference = values - x[f];
    sum += difference * difference;
  }
  return sum;
}

// The sum of rbf_sum (two vectors of lanes per step, then one, then a padded tail with
// zero coefficients), in Lanes of the width the variant was built for.
template <typename Lanes>
__attribute__((always_inline)) inline double sum_lanes(const double* const* columns, std::size_t feature_count,
                                                       const double* x, double gamma, const double* coefficients,
                                                       std::size_t count) {
  constexpr std::size_t width = sizeof(Lanes) / sizeof(double);
  const Lanes factor = splat<Lanes>(-gamma);
  Lanes sum = splat<Lanes>(0.0), other_sum = splat<Lanes>(0.0);
  std::size_t k = 0;
  for (; k + 2 * width <= count; k += 2 * width) {
    const Lanes squared = squared_distance<Lanes>(columns, feature_count, x, k, width);
    const Lanes other_squared = squared_distance<Lanes>(columns, feature_count, x, k + width, width);
    sum += load<Lanes>(coefficients + k) * exp_lanes(squared, factor);
    other_sum += load<Lanes>(coefficients + k + width) * exp_lanes(other_squared, factor);
  }
  sum += other_sum;
  for (; k + width <= count; k += width)
    sum += load<Lanes>(coefficients + k) * exp_lanes(squared_distance<Lanes>(columns, feature_count, x, k, width), factor);
  if (k < count) {
    const std::size_t rest = count - k;
    double weights[width] = {};
    std::memcpy(weights, coefficients + k, rest * sizeof(double));
    sum += load<Lanes>(weights) * exp_lanes(squared_distance<Lanes>(columns, feature_count, x, k, rest), factor);
  }
  double lanes[width];
  std::memcpy(lanes, &sum, sizeof sum);
  double total = 0;
  for (std::size_t i = 0; i < width; i += 2) total += lanes[i] + lanes[i + 1];
  return total;
}

__attribute__((target("avx512f,fma"))) double sum_avx512(const double* const* columns, std::size_t feature_count,
                                                         const double* x, double gamma, const double* coefficients,
                                                         std::size_t count) {
  return sum_lanes<Lanes8>(columns, feature_count, x, gamma, coefficients, count);
}

__attribute__((target("avx2,fma"))) double sum_avx2(const double* const* columns, std::size_t feature_count,
                                                    const double* x, double gamma, const double* coefficients,
                                                    std::size_t count) {
  return sum_lanes<Lanes4>(columns, feature_count, x, gamma, coefficients, count);
}

}  // namespace

std::vector<RbfSumVariant> rbf_sum_variants() {
  __builtin_cpu_init();
  std::vector<RbfSumVariant> variants;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("fma"))
    variants.push_back({"avx512-fma", sum_avx512});
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) variants.push_back({"avx2-fma", sum_avx2});
  variants.push_back({"exact", rbf_sum});
  return variants;
}
#else
std::vector<RbfSumVariant> rbf_sum_variants() { return {{"exact", rbf_sum}}; }
#endif

namespace {
const RbfSumVariant& fast_variant() {
  static const RbfSumVariant chosen = rbf_sum_variants().front();
  return chosen;
}
}  // namespace

double rbf_sum_fast(const double* const* columns, std::size_t feature_count, const double* x, double gamma,
                    const double* coefficients, std::size_t count) {
  return fast_variant().sum(columns, feature_count, x, gamma, coefficients, count);
}

const char* rbf_sum_fast_arithmetic() { return fast_variant().name; }

}  // namespace thermodrift::svr_detail
