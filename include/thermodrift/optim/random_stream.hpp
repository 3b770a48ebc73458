// Counter-based random streams: stream (seed, a, b) is a pure function of its three
// numbers, so fish i in iteration t draws the same numbers whichever thread, batch or
// order it is handled in. That is what makes results independent of the thread count.
//
// Generator: xoshiro256** (Blackman & Vigna) seeded through splitmix64. The uniform and
// normal transforms are written here rather than taken from <random>, whose
// distributions differ between standard libraries.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

#include <Eigen/Core>

namespace thermodrift::optim {

class RandomStream {
 public:
  RandomStream(std::uint64_t seed, std::uint64_t stream, std::uint64_t substream = 0) {
    std::uint64_t key = mix64(seed);
    key = mix64(key ^ mix64(stream + 0x632be59bd9b4e019ULL));
    key = mix64(key ^ mix64(substream + 0x8cb92ba72f3d8dd7ULL));
    for (std::uint64_t k = 0; k < 4; ++k) state_[k] = mix64(key + (k + 1) * kGolden);
  }

  std::uint64_t next() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double low, double high) { return low + (high - low) * uniform(); }

  // Standard normal by Box-Muller.
  double normal() {
    const double radius = std::sqrt(-2.0 * std::log1p(-uniform()));  // log(1-u), u < 1
    return radius * std::cos(2.0 * std::numbers::pi * uniform());
  }

  // Uniform in the unit cube [0, 1)^dim.
  Eigen::VectorXd unit_cube_point(Eigen::Index dim) {
    Eigen::VectorXd point(dim);
    for (Eigen::Index d = 0; d < dim; ++d) point[d] = uniform();
    return point;
  }

  // Uniform in the Euclidean ball of `radius` about the origin: a normal direction,
  // and a length r·U^(1/dim) because the volume within length s grows as s^dim.
  Eigen::VectorXd ball_offset(Eigen::Index dim, double radius) {
    Eigen::VectorXd direction(dim);
    double norm = 0.0;
    while (norm == 0.0) {
      for (Eigen::Index d = 0; d < dim; ++d) direction[d] = normal();
      norm = direction.norm();
    }
    const double length = radius * std::pow(uniform(), 1.0 / static_cast<double>(dim));
    return direction * (length / norm);
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  static constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;
  // splitmix64's output function: a bijective 64-bit mix.
  static std::uint64_t mix64(std::uint64_t x) {
    std::uint64_t z = x + kGolden;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }

  std::uint64_t state_[4];
};

}  // namespace thermodrift::optim
