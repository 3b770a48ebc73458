#include "thermodrift/sim/simulator.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "thermodrift/error.hpp"
#include "sim/readout.hpp"

namespace thermodrift::sim {
namespace {

// Exact one-step update of the first-order lag τ·x' = u - x when the input moves
// linearly from u0 to u1 over the step dt (first-order hold):
//   x1 = a·x0 + (1 - a)·u0 + c·(u1 - u0),  a = exp(-dt/τ),  c = 1 - τ·(1 - a)/dt.
// With a steady ramp u = r·t it keeps x = u - r·τ exactly; for τ → 0 it gives x1 = u1.
class FirstOrderLag {
 public:
  FirstOrderLag(double time_constant_s, double dt_s)
      : a_(std::exp(-dt_s / time_constant_s)), c_(1.0 - time_constant_s * (1.0 - a_) / dt_s) {}
  double step(double x0, double u0, double u1) const { return a_ * x0 + (1.0 - a_) * u0 + c_ * (u1 - u0); }

 private:
  double a_;
  double c_;
};

// The thermal state of one axis and the drift law evaluated on it.
class AxisPhysics {
 public:
  AxisPhysics(const SimulatedAxis& model, const SimulatorOptions& options, double dt_s)
      : model_(model),
        reference_c_(options.reference_temperature_c),
        hysteresis_scale_c_per_s_(options.hysteresis_rate_scale_c_per_min / 60.0),
        housing_lag_(model.sensor_time_constant_s, dt_s),
        coil_lag_(model.coil_time_constant_s, dt_s),
        gradient_lag_(model.gradient_time_constant_s, dt_s),
        hysteresis_lag_(model.hysteresis_time_constant_s, dt_s),
        housing_c_(options.start_temperature_c),
        coil_c_(options.start_temperature_c) {}  // starts in equilibrium with the room

  double housing_c() const { return housing_c_; }
  double coil_c() const { return coil_c_; }
  double gradient_c() const { return gradient_c_; }
  double hysteresis() const { return hysteresis_; }

  // dTc/dt from the coil's own equation, τc·Tc' = Th - Tc (°C/s).
  double coil_rate_c_per_s() const { return (housing_c_ - coil_c_) / model_.coil_time_constant_s; }

  // True drift (°/h):
  //   b + D_T·ΔTc + D_T2·ΔTc² + D_dT·dTc/dt + D_∇T·d(∇T)/dt + D_h·h,
  // rates in °C/min, d(∇T)/dt from the gradient's equation τg·∇T' = G·dTc/dt - ∇T.
  double drift_dph() const {
    const double delta_c = coil_c_ - reference_c_;
    const double coil_rate = coil_rate_c_per_s();
    const double gradient_rate = (model_.gradient_gain_s * coil_rate - gradient_c_) / model_.gradient_time_constant_s;
    return model_.bias_dph + model_.temperature_dph_per_c * delta_c +
           model_.temperature2_dph_per_c2 * delta_c * delta_c +
           model_.rate_dph_per_c_per_min * coil_rate * 60.0 +
           model_.gradient_rate_dph_per_c_per_min * gradient_rate * 60.0 +
           model_.hysteresis_dph * hysteresis_;
  }

  // Advances one sample while the chamber moves linearly from chamber0 to chamber1.
  void step(double chamber0_c, double chamber1_c) {
    const double coil_rate0 = coil_rate_c_per_s();
    const double housing1 = housing_lag_.step(housing_c_, chamber0_c, chamber1_c);
    const double coil1 = coil_lag_.step(coil_c_, housing_c_, housing1);
    housing_c_ = housing1;
    coil_c_ = coil1;
    const double coil_rate1 = coil_rate_c_per_s();
    gradient_c_ = gradient_lag_.step(gradient_c_, model_.gradient_gain_s * coil_rate0,
                                     model_.gradient_gain_s * coil_rate1);
    hysteresis_ = hysteresis_lag_.step(hysteresis_, heating_state(coil_rate0), heating_state(coil_rate1));
  }

 private:
  // +1 heating, -1 cooling, smooth through zero: tanh(dTc/dt / scale).
  double heating_state(double coil_rate_c_per_s) const {
    return std::tanh(coil_rate_c_per_s / hysteresis_scale_c_per_s_);
  }

  SimulatedAxis model_;
  double reference_c_;
  double hysteresis_scale_c_per_s_;
  FirstOrderLag housing_lag_;
  FirstOrderLag coil_lag_;
  FirstOrderLag gradient_lag_;
  FirstOrderLag hysteresis_lag_;
  double housing_c_;
  double coil_c_;
  double gradient_c_ = 0.0;  // radial gradient across the coil, °C
  double hysteresis_ = 0.0;  // smoothed heating/cooling state in [-1, 1]
};

// What the unit outputs for one axis: true drift plus white noise (ARW), a first-order
// Gauss-Markov bias (bias instability) and the quantization of a pulse output whose
// remainder carries over to the next sample.
class AxisNoise {
 public:
  AxisNoise(const NoiseOptions& noise, double dt_s, std::uint64_t seed, int axis)
      : white_std_dph_(noise.angle_random_walk_deg_per_sqrt_h * 60.0 / std::sqrt(dt_s)),
        bias_phi_(std::exp(-dt_s / noise.bias_correlation_time_s)),
        bias_std_dph_(bias_process_std_dph(noise)),
        pulses_(noise.quantization_arcsec, dt_s),
        temperature_noise_c_(noise.temperature_noise_c),
        temperature_resolution_c_(noise.temperature_resolution_c),
        white_(derive_seed(seed, 3 * axis)),
        bias_(derive_seed(seed, 3 * axis + 1)),
        thermometer_(derive_seed(seed, 3 * axis + 2)) {
    bias_dph_ = bias_std_dph_ * bias_();  // start from the stationary distribution
  }

  // Measured rate (°/h) for this sample.
  double gyro_dph(double drift_dph) {
    const double rate = drift_dph + white_std_dph_ * white_() + bias_dph_;
    bias_dph_ = bias_phi_ * bias_dph_ + bias_std_dph_ * std::sqrt(1.0 - bias_phi_ * bias_phi_) * bias_();
    return pulses_(rate);
  }

  // Thermometer reading of the housing temperature.
  double temperature_c(double housing_c) {
    const double reading = housing_c + temperature_noise_c_ * thermometer_();
    return at_resolution(reading, temperature_resolution_c_);
  }

 private:
  double white_std_dph_;
  double bias_phi_;
  double bias_std_dph_;
  PulseOutput pulses_;
  double temperature_noise_c_;
  double temperature_resolution_c_;
  StandardNormal white_;
  StandardNormal bias_;
  StandardNormal thermometer_;
  double bias_dph_ = 0.0;
};

}  // namespace

ChamberRun simulate(const SimulatorOptions& options, const StopToken& stop) {
  const ChamberProfile profile(options);  // validates the options
  const double dt_s = 1.0 / options.rate_hz;
  const auto rows = static_cast<std::size_t>(std::llround(std::floor(profile.duration_s() * options.rate_hz + 1e-9)));

  ChamberRun run;
  run.rate_hz = options.rate_hz;
  run.cycle_start_s = profile.cycle_starts_s();
  for (std::string_view name : chamber_run_columns) run.column_names.emplace_back(name);
  if (options.record_internal_states) {
    for (std::string_view name : internal_state_columns) run.column_names.emplace_back(name);
  }
  run.columns.assign(run.column_names.size(), std::vector<double>(rows));

  std::vector<AxisPhysics> physics;
  std::vector<AxisNoise> noise;
  for (int axis = 0; axis < 3; ++axis) {
    physics.emplace_back(options.axes[axis], options, dt_s);
    noise.emplace_back(options.noise, dt_s, options.seed, axis);
  }

  // Column offsets in chamber_run_columns / internal_state_columns order.
  constexpr std::size_t time_col = 0, chamber_col = 1, temp_col = 2, gyro_col = 5, drift_col = 8;
  constexpr std::size_t coil_col = 11, gradient_col = 14, hysteresis_col = 17;

  double chamber_c = profile.temperature_c(0.0);
  for (std::size_t k = 0; k < rows; ++k) {
    if (k % 4096 == 0) stop.throw_if_requested("simulation");
    const double time_s = static_cast<double>(k) * dt_s;
    run.columns[time_col][k] = time_s;
    run.columns[chamber_col][k] = chamber_c;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double drift = physics[axis].drift_dph();
      run.columns[temp_col + axis][k] = noise[axis].temperature_c(physics[axis].housing_c());
      run.columns[gyro_col + axis][k] = noise[axis].gyro_dph(drift);
      run.columns[drift_col + axis][k] = drift;
      if (options.record_internal_states) {
        run.columns[coil_col + axis][k] = physics[axis].coil_c();
        run.columns[gradient_col + axis][k] = physics[axis].gradient_c();
        run.columns[hysteresis_col + axis][k] = physics[axis].hysteresis();
      }
    }
    const double next_chamber_c = profile.temperature_c(static_cast<double>(k + 1) * dt_s);
    for (AxisPhysics& axis : physics) axis.step(chamber_c, next_chamber_c);
    chamber_c = next_chamber_c;
  }
  return run;
}

}  // namespace thermodrift::sim
