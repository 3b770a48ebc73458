#include "thermodrift/report/allan.hpp"

#include <fmt/format.h>

#include <cmath>

#include "thermodrift/error.hpp"

namespace thermodrift {

std::vector<AllanPoint> overlapping_allan_deviation(std::span<const double> rate, double sample_rate_hz,
                                                    int points_per_decade, double max_tau_fraction) {
  if (!(sample_rate_hz > 0) || !std::isfinite(sample_rate_hz)) {
    throw UsageError(fmt::format("Allan deviation: sample rate {} Hz is not positive", sample_rate_hz));
  }
  if (points_per_decade < 1) throw UsageError("Allan deviation: points per decade must be at least 1");
  if (!(max_tau_fraction > 0 && max_tau_fraction <= 0.5)) {
    throw UsageError(fmt::format("Allan deviation: largest τ fraction {} is outside (0, 0.5]", max_tau_fraction));
  }
  std::vector<AllanPoint> points;
  const std::size_t n = rate.size();
  if (n < 3) return points;
  const double tau0 = 1.0 / sample_rate_hz;
  // Phase (integrated rate) with the mean removed first: the cumulative sum of a large
  // constant bias would otherwise cost digits in the second differences.
  double mean = 0;
  for (double y : rate) mean += y;
  mean /= static_cast<double>(n);
  std::vector<double> phase(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) phase[k + 1] = phase[k] + (rate[k] - mean) * tau0;

  const auto largest = std::max<std::size_t>(1, static_cast<std::size_t>(max_tau_fraction * static_cast<double>(n)));
  std::size_t previous = 0;
  for (int step = 0;; ++step) {
    const double exact = std::pow(10.0, static_cast<double>(step) / points_per_decade);
    const auto m = static_cast<std::size_t>(std::floor(exact + 1e-9));
    if (m > largest || 2 * m > n) break;
    if (m == previous) continue;
    previous = m;
    const std::size_t terms = n - 2 * m + 1;
    double sum = 0;
    for (std::size_t k = 0; k < terms; ++k) {
      const double d = phase[k + 2 * m] - 2.0 * phase[k + m] + phase[k];
      sum += d * d;
    }
    const double tau = static_cast<double>(m) * tau0;
    points.push_back({tau, std::sqrt(sum / (2.0 * tau * tau * static_cast<double>(terms))), terms});
  }
  return points;
}

}  // namespace thermodrift
