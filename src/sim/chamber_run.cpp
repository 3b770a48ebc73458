#include "thermodrift/sim/chamber_run.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>

#include <fmt/format.h>

#include "thermodrift/error.hpp"

namespace thermodrift::sim {
namespace {

// Samples in a window of `window_s` seconds, at least one.
std::size_t window_samples(double window_s, double rate_hz) {
  if (!std::isfinite(window_s) || window_s < 0.0) {
    throw UsageError(fmt::format("smoothing window must be a non-negative number of seconds, got {}", window_s));
  }
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(window_s * rate_hz)));
}

}  // namespace

const std::vector<double>& ChamberRun::column(std::string_view name) const {
  const auto found = std::find(column_names.begin(), column_names.end(), name);
  if (found == column_names.end()) throw UsageError(fmt::format("chamber run has no column '{}'", name));
  return columns[static_cast<std::size_t>(found - column_names.begin())];
}

std::vector<std::size_t> ChamberRun::cycle_start_rows() const {
  std::vector<std::size_t> starts;
  for (double start_s : cycle_start_s) {
    starts.push_back(std::min(rows(), static_cast<std::size_t>(std::llround(std::ceil(start_s * rate_hz - 1e-9)))));
  }
  return starts;
}

std::array<double, 3> ChamberRun::noise_floor(double window_s, std::size_t first_row) const {
  const std::size_t window = window_samples(window_s, rate_hz);
  std::array<double, 3> floor{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::vector<double>& gyro = column(gyro_columns[axis]);
    const std::vector<double>& drift = column(drift_columns[axis]);
    if (gyro.size() < window) throw UsageError("smoothing window is longer than the run");
    if (first_row + 1 >= gyro.size()) throw UsageError("the noise floor needs at least two rows from its first row on");
    // Trailing mean over the last `window` noise samples, kept as a running sum.
    std::vector<double> smoothed;
    smoothed.reserve(gyro.size() - window + 1);
    double sum = 0.0;
    for (std::size_t k = 0; k < gyro.size(); ++k) {
      sum += gyro[k] - drift[k];
      if (k >= window) sum -= gyro[k - window] - drift[k - window];
      if (k + 1 >= window && k >= first_row) smoothed.push_back(sum / static_cast<double>(window));
    }
    double mean = 0.0;
    for (double value : smoothed) mean += value;
    mean /= static_cast<double>(smoothed.size());
    double variance = 0.0;
    for (double value : smoothed) variance += (value - mean) * (value - mean);
    floor[axis] = variance / static_cast<double>(smoothed.size());
  }
  return floor;
}

LogSpec log_spec() {
  LogSpec spec;
  spec.time_column = std::string(time_column);
  for (std::size_t axis = 0; axis < 3; ++axis) {
    spec.gyro_columns.emplace_back(gyro_columns[axis]);
    spec.temperature_columns.emplace_back(temperature_columns[axis]);
  }
  return spec;
}

ChamberLog to_chamber_log(const ChamberRun& run) {
  ChamberLog log;
  log.source = "simulated";
  log.time = run.column(time_column);
  for (std::size_t axis = 0; axis < 3; ++axis) {
    log.gyro_names.emplace_back(gyro_columns[axis]);
    log.gyro.push_back(run.column(gyro_columns[axis]));
    log.temperature_names.emplace_back(temperature_columns[axis]);
    log.temperature.push_back(run.column(temperature_columns[axis]));
  }
  log.line.resize(log.rows());
  for (std::size_t i = 0; i < log.rows(); ++i) log.line[i] = i + 2;  // as write_csv writes it: a header, then rows
  return log;
}

std::optional<std::vector<std::string>> true_drift_columns(const std::vector<std::string>& gyro_names) {
  std::vector<std::string> drift;
  for (const auto& name : gyro_names) {
    if (name.rfind("gyro_", 0) != 0) return std::nullopt;
    drift.push_back("drift_" + name.substr(5));
  }
  return drift;
}

double expected_noise_floor(const NoiseOptions& noise, double rate_hz, double window_s) {
  const std::size_t window = window_samples(window_s, rate_hz);
  const double w = static_cast<double>(window);
  const double dt_s = 1.0 / rate_hz;
  const double white_std = noise.angle_random_walk_deg_per_sqrt_h * 60.0 / std::sqrt(dt_s);
  const double white = white_std * white_std / w;
  // Mean of w samples of an AR(1) process with coefficient φ and variance σ²:
  //   σ²/w² · (w + 2·Σ_{j=1}^{w-1} (w - j)·φ^j).
  const double bias_std = bias_process_std_dph(noise);
  const double phi = std::exp(-dt_s / noise.bias_correlation_time_s);
  double correlation_sum = w;
  double phi_j = 1.0;
  for (std::size_t j = 1; j < window; ++j) {
    phi_j *= phi;
    correlation_sum += 2.0 * (w - static_cast<double>(j)) * phi_j;
  }
  const double bias = bias_std * bias_std * correlation_sum / (w * w);
  // The carried remainder r is uniform on ±q/2: the window's mean rate error is
  // (r_k - r_{k-w}) / (w·dt), of variance 2·(q²/12) / (w·dt)².
  const double q = noise.quantization_arcsec;
  const double quantization = 2.0 * q * q / 12.0 / ((w * dt_s) * (w * dt_s));
  return white + bias + quantization;
}

void write_csv(const ChamberRun& run, std::ostream& out, const StopToken& stop) {
  fmt::memory_buffer line;
  for (std::size_t c = 0; c < run.column_names.size(); ++c) {
    fmt::format_to(std::back_inserter(line), "{}{}", c == 0 ? "" : ",", run.column_names[c]);
  }
  line.push_back('\n');
  out.write(line.data(), static_cast<std::streamsize>(line.size()));
  for (std::size_t k = 0; k < run.rows(); ++k) {
    if (k % 4096 == 0) stop.throw_if_requested("writing the log");
    line.clear();
    for (std::size_t c = 0; c < run.columns.size(); ++c) {
      if (c == 0) {
        fmt::format_to(std::back_inserter(line), "{}", run.columns[c][k]);
      } else {
        fmt::format_to(std::back_inserter(line), ",{:.9g}", run.columns[c][k]);
      }
    }
    line.push_back('\n');
    out.write(line.data(), static_cast<std::streamsize>(line.size()));
  }
}

}  // namespace thermodrift::sim
