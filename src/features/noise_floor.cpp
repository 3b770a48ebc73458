#include "thermodrift/features/noise_floor.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "thermodrift/error.hpp"
#include "thermodrift/features/moving_average.hpp"

namespace thermodrift {

namespace {

// Median of χ²₁: a Gaussian d of variance v has median(d²) = 0.4549·v.
constexpr double kChiSquareOneMedian = 0.454936;
// E[d²] of the Hadamard difference of three window means of white noise, in units of σ²/w.
constexpr double kHadamardFactor = 6.0;

// Appends the squared second differences of overlapping trailing window means of one
// series. Window means are taken as the pipeline takes them (TrailingMean); m(t - τ) is
// the last full mean at or before t - τ.
void append_squared_differences(std::span<const double> time, std::span<const double> gyro, double window_s,
                                std::vector<double>& squares) {
  if (time.size() != gyro.size()) {
    throw UsageError(fmt::format("noise floor: {} times for {} gyro values", time.size(), gyro.size()));
  }
  TrailingMean mean(window_s);
  struct Stamped {
    double time;
    double mean;
  };
  std::vector<Stamped> full;  // full window means since the last gap
  std::size_t lag1 = 0, lag2 = 0;
  for (std::size_t i = 0; i < time.size(); ++i) {
    if (i > 0 && time[i] - time[i - 1] > window_s) {
      mean.reset();
      full.clear();
      lag1 = lag2 = 0;
    }
    const double m = mean.push(time[i], gyro[i]);
    if (!mean.full()) continue;
    full.push_back({time[i], m});
    const double t = time[i];
    while (lag1 + 1 < full.size() && full[lag1 + 1].time <= t - window_s) ++lag1;
    while (lag2 + 1 < full.size() && full[lag2 + 1].time <= t - 2 * window_s) ++lag2;
    if (full[lag2].time > t - 2 * window_s || full[lag1].time > t - window_s) continue;
    const double d = m - 2 * full[lag1].mean + full[lag2].mean;
    squares.push_back(d * d);
  }
}

NoiseFloorEstimate from_squares(std::vector<double>& squares) {
  NoiseFloorEstimate estimate;
  estimate.differences = squares.size();
  if (squares.empty()) return estimate;
  const auto middle = squares.begin() + static_cast<std::ptrdiff_t>(squares.size() / 2);
  std::nth_element(squares.begin(), middle, squares.end());
  estimate.variance = *middle / (kHadamardFactor * kChiSquareOneMedian);
  return estimate;
}

void check_window(double window_s) {
  if (!(std::isfinite(window_s) && window_s > 0)) {
    throw UsageError(fmt::format("noise floor: the window must be > 0 s, not {}", window_s));
  }
}

}  // namespace

NoiseFloorEstimate estimate_noise_floor(std::span<const double> time, std::span<const double> gyro,
                                        double window_s) {
  check_window(window_s);
  std::vector<double> squares;
  append_squared_differences(time, gyro, window_s, squares);
  return from_squares(squares);
}

NoiseFloorEstimate estimate_noise_floor(const std::vector<ChamberLog>& logs, std::size_t axis, double window_s) {
  check_window(window_s);
  std::vector<double> squares;
  for (const auto& log : logs) append_squared_differences(log.time, log.gyro.at(axis), window_s, squares);
  return from_squares(squares);
}

}  // namespace thermodrift
