#include "thermodrift/sim/options.hpp"

#include <cmath>
#include <string>

#include <fmt/format.h>

namespace thermodrift::sim {

std::array<SimulatedAxis, 3> default_simulated_axes() {
  SimulatedAxis x;  // the struct defaults are axis x

  SimulatedAxis y;
  y.sensor_time_constant_s = 240.0;
  y.coil_time_constant_s = 650.0;
  y.gradient_gain_s = 90.0;
  y.gradient_time_constant_s = 300.0;
  y.hysteresis_time_constant_s = 1200.0;
  y.bias_dph = -0.3;
  y.temperature_dph_per_c = -0.045;
  y.temperature2_dph_per_c2 = 8.0e-4;
  y.rate_dph_per_c_per_min = -0.8;
  y.gradient_rate_dph_per_c_per_min = -2.0;
  y.hysteresis_dph = 0.5;

  SimulatedAxis z;
  z.sensor_time_constant_s = 150.0;
  z.coil_time_constant_s = 880.0;
  z.gradient_gain_s = 45.0;
  z.gradient_time_constant_s = 200.0;
  z.hysteresis_time_constant_s = 600.0;
  z.bias_dph = 0.2;
  z.temperature_dph_per_c = 0.015;
  z.temperature2_dph_per_c2 = -1.0e-3;
  z.rate_dph_per_c_per_min = 2.0;
  z.gradient_rate_dph_per_c_per_min = 4.0;
  z.hysteresis_dph = -0.4;

  return {x, y, z};
}

double bias_process_std_dph(const NoiseOptions& noise) {
  return noise.bias_instability_dph * 0.6643 / 0.6174;
}

namespace {

// Records the first failed check; `ok` stays false from then on.
class Checker {
 public:
  void require(bool condition, const std::string& message) {
    if (ok_ && !condition) {
      ok_ = false;
      message_ = message;
    }
  }
  void finite(double value, const char* name) {
    require(std::isfinite(value), fmt::format("{} must be a finite number, got {}", name, value));
  }
  void positive(double value, const char* name) {
    finite(value, name);
    require(value > 0.0, fmt::format("{} must be positive, got {}", name, value));
  }
  void non_negative(double value, const char* name) {
    finite(value, name);
    require(value >= 0.0, fmt::format("{} must not be negative, got {}", name, value));
  }
  bool ok() const { return ok_; }
  const std::string& message() const { return message_; }

 private:
  bool ok_ = true;
  std::string message_;
};

void check_axis(Checker& check, const SimulatedAxis& axis) {
  check.positive(axis.sensor_time_constant_s, "sensor_time_constant_s");
  check.positive(axis.coil_time_constant_s, "coil_time_constant_s");
  check.non_negative(axis.gradient_gain_s, "gradient_gain_s");
  check.positive(axis.gradient_time_constant_s, "gradient_time_constant_s");
  check.positive(axis.hysteresis_time_constant_s, "hysteresis_time_constant_s");
  check.finite(axis.bias_dph, "bias_dph");
  check.finite(axis.temperature_dph_per_c, "temperature_dph_per_c");
  check.finite(axis.temperature2_dph_per_c2, "temperature2_dph_per_c2");
  check.finite(axis.rate_dph_per_c_per_min, "rate_dph_per_c_per_min");
  check.finite(axis.gradient_rate_dph_per_c_per_min, "gradient_rate_dph_per_c_per_min");
  check.finite(axis.hysteresis_dph, "hysteresis_dph");
}

}  // namespace

bool SimulatorOptions::IsValid(std::string* error) const {
  // Bounds a run to what fits comfortably in memory (20 columns of doubles).
  constexpr double max_rows = 5.0e7;

  Checker check;
  check.require(cycles >= 1 && cycles <= 1000,
                fmt::format("cycles must be between 1 and 1000, got {}", cycles));
  check.positive(rate_hz, "rate_hz");
  check.require(rate_hz <= 10000.0, fmt::format("rate_hz must be at most 10000, got {}", rate_hz));
  check.finite(chamber_min_c, "chamber_min_c");
  check.finite(chamber_max_c, "chamber_max_c");
  check.finite(start_temperature_c, "start_temperature_c");
  check.require(chamber_min_c < chamber_max_c,
                fmt::format("chamber_min_c ({}) must be below chamber_max_c ({})", chamber_min_c,
                            chamber_max_c));
  check.require(start_temperature_c >= chamber_min_c && start_temperature_c <= chamber_max_c,
                fmt::format("start_temperature_c ({}) must lie within the chamber range [{}, {}]",
                            start_temperature_c, chamber_min_c, chamber_max_c));
  check.positive(ramp_rate_c_per_min, "ramp_rate_c_per_min");
  check.non_negative(extreme_soak_min, "extreme_soak_min");
  check.non_negative(start_soak_min, "start_soak_min");
  check.finite(reference_temperature_c, "reference_temperature_c");
  check.positive(hysteresis_rate_scale_c_per_min, "hysteresis_rate_scale_c_per_min");
  for (const SimulatedAxis& axis : axes) check_axis(check, axis);

  check.non_negative(noise.angle_random_walk_deg_per_sqrt_h, "angle_random_walk_deg_per_sqrt_h");
  check.non_negative(noise.bias_instability_dph, "bias_instability_dph");
  check.positive(noise.bias_correlation_time_s, "bias_correlation_time_s");
  check.non_negative(noise.quantization_arcsec, "quantization_arcsec");
  check.non_negative(noise.temperature_noise_c, "temperature_noise_c");
  check.non_negative(noise.temperature_resolution_c, "temperature_resolution_c");

  if (check.ok()) {
    const double span_c = chamber_max_c - chamber_min_c;
    const double cycle_min = start_soak_min + 2.0 * extreme_soak_min + 2.0 * span_c / ramp_rate_c_per_min;
    const double rows = cycles * cycle_min * 60.0 * rate_hz;
    check.require(rows >= 2.0, "the run must hold at least two samples");
    check.require(rows <= max_rows,
                  fmt::format("the run would hold {:.3g} samples, more than {:.3g}", rows, max_rows));
  }
  if (!check.ok() && error != nullptr) *error = check.message();
  return check.ok();
}

}  // namespace thermodrift::sim
