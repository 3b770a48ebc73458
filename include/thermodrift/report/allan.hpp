// Overlapping Allan deviation of a rate series (IEEE Std 952 / 1554), the way the field
// judges a gyro before and after compensation.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace thermodrift {

struct AllanPoint {
  double tau_s = 0;        // averaging time τ = m / rate
  double deviation = 0;    // σ(τ), in the unit of the input rate
  std::size_t terms = 0;   // second differences averaged: N - 2m + 1
};

// Overlapping Allan deviation of `rate` (evenly sampled at `sample_rate_hz`) at cluster
// sizes m on a logarithmic grid (`points_per_decade`, duplicates removed), m from 1 up to
// `max_tau_fraction` of the series. With the phase x_k = τ0 Σ_{i<k} y_i (k = 0..N),
//
//   σ²(τ) = 1 / (2 τ² (N - 2m + 1)) · Σ_{k=0}^{N-2m} (x_{k+2m} - 2 x_{k+m} + x_k)²,
//
// which is O(N) per τ through the cumulative sum. Fewer than 3 samples give no points.
// Throws UsageError for a rate ≤ 0, points_per_decade < 1 or a fraction outside (0, 0.5].
std::vector<AllanPoint> overlapping_allan_deviation(std::span<const double> rate, double sample_rate_hz,
                                                    int points_per_decade = 10,
                                                    double max_tau_fraction = 0.25);

}  // namespace thermodrift
