// Settings of the chamber-test simulator: the chamber profile, the thermal and drift
// model of each gyro axis, and the noise. Every field has a default; the defaults are a
// navigation-grade 3-axis FOG in a -40..60 °C chamber cycled at 1 °C/min, and they are
// documented with their equations in docs/simulator.md.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace thermodrift::sim {

// Thermal path and drift law of one gyro axis. Drift in °/h, temperatures in °C,
// temperature rates in °C/min (the project's units). The default is axis x.
struct SimulatedAxis {
  // --- thermal path: chamber air -> housing (where the sensor sits) -> fiber coil ---
  double sensor_time_constant_s = 180.0;      // housing/sensor lag behind the chamber air
  double coil_time_constant_s = 420.0;        // fiber coil lag behind the housing
  double gradient_gain_s = 60.0;              // steady radial gradient per coil rate: ∇T = gain·dTc/dt
  double gradient_time_constant_s = 240.0;    // lag of the radial gradient behind that steady value
  double hysteresis_time_constant_s = 900.0;  // memory of the heating/cooling state
  // --- drift law (IEEE Std 952 terms plus nonlinear ones), evaluated on the coil ---
  double bias_dph = 0.5;                      // drift at the reference temperature
  double temperature_dph_per_c = 0.030;       // D_T: per °C of ΔTc
  double temperature2_dph_per_c2 = 4.0e-4;    // per °C² of ΔTc² (nonlinear)
  double rate_dph_per_c_per_min = 1.2;        // D_dT: per °C/min of dTc/dt
  double gradient_rate_dph_per_c_per_min = 3.0;  // D_∇T: per °C/min of d(∇T)/dt (Shupe)
  double hysteresis_dph = 0.3;                // heating minus cooling offset / 2, at saturation
};

// The three default axes. They differ in every coefficient and time constant, some in
// sign, so the axes do not share one drift law (the paper's cross-axis experiment).
std::array<SimulatedAxis, 3> default_simulated_axes();

// Rate noise of every axis (same for all three) and of the temperature sensors.
struct NoiseOptions {
  double angle_random_walk_deg_per_sqrt_h = 0.003;  // ARW: white rate noise, σ = ARW·60·√rate_hz °/h
  double bias_instability_dph = 0.01;     // Allan-deviation floor the bias process produces
  double bias_correlation_time_s = 600.0; // correlation time of the Gauss-Markov bias
  double quantization_arcsec = 0.05;      // angle quantum of the pulse output (0: off)
  double temperature_noise_c = 0.005;     // white noise std of each temperature reading
  double temperature_resolution_c = 0.001;  // resolution of the temperature readings (0: off)
};

// Stationary std (°/h) of the first-order Gauss-Markov bias: its Allan-deviation peak,
// 0.6174·σ at T ≈ 1.89·τ, equals the flicker floor 0.664·B that defines bias instability B
// (IEEE Std 952 Annex C), so σ = B·0.6643/0.6174 ≈ 1.076·B.
double bias_process_std_dph(const NoiseOptions& noise);

struct SimulatorOptions {
  std::uint64_t seed = 1;                 // seeds every noise stream; true drift does not depend on it
  int cycles = 2;                         // number of chamber cycles
  double rate_hz = 1.0;                   // output sample rate
  double chamber_min_c = -40.0;           // cold extreme of the chamber
  double chamber_max_c = 60.0;            // hot extreme of the chamber
  double start_temperature_c = 20.0;      // room temperature where each cycle starts and ends
  double ramp_rate_c_per_min = 1.0;       // chamber ramp rate, heating and cooling
  double extreme_soak_min = 60.0;         // soak at each extreme
  double start_soak_min = 60.0;           // soak at the start temperature at the start of each cycle
  bool heat_first = true;                 // a cycle goes start -> hot -> cold -> start (else cold first)
  double reference_temperature_c = 20.0;  // ΔTc = Tc - reference in the drift law
  double hysteresis_rate_scale_c_per_min = 0.2;  // coil rate at which the heating/cooling state saturates
  std::array<SimulatedAxis, 3> axes = default_simulated_axes();  // x, y, z
  NoiseOptions noise;                     // rate and temperature noise
  bool record_internal_states = false;    // append coil_*, gradient_*, hysteresis_* columns

  // True when every option is usable; otherwise false with the reason in `*error`
  // (when error is not null).
  bool IsValid(std::string* error) const;
};

}  // namespace thermodrift::sim
