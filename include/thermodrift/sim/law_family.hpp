// A family of FOG units and chamber profiles drawn by seed: thermal networks, drift laws,
// noise and temperature programmes nobody picked by hand. Identification is developed on
// the development seeds and judged on the disjoint acceptance seeds (docs/simulator.md,
// "The law family"); nothing is tuned on the acceptance list.
//
//   sim::UnitLaw unit = sim::draw_unit(law_seed);
//   sim::Setpoint training = sim::draw_profile(sim::ProfileKind::cycle, unit, profile_seed, 2);
//   sim::ChamberRun run = sim::simulate_unit(unit, training, noise_seed);
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "thermodrift/sim/chamber_run.hpp"

namespace thermodrift::sim {

// Seeds of the laws identification is developed on, and of the laws it is accepted on.
// Disjoint; the acceptance list is only ever run by the benchmark and acceptance tests.
std::vector<std::uint64_t> development_law_seeds();  // 1..40
std::vector<std::uint64_t> acceptance_law_seeds();   // 9001..9060

// Drift that remembers the direction of the last temperature movement.
enum class HysteresisKind {
  none,
  memory,  // τh·h' = tanh((dTc/dt) / r0) - h: a heating (+1) / cooling (-1) state that fades
  play,    // backlash: p follows Tc at a distance w; drift ∝ (Tc - p)/w in -1..1
};

// Static drift of the coil temperature: a polynomial, or a smooth step on top of a line.
enum class StaticShape { polynomial, tanh_step };

// One gyro axis: a chain of 1-3 thermal nodes from the unit's case to the fiber coil (the
// last node), its temperature sensor, and the drift law evaluated on the chain.
struct AxisLaw {
  std::vector<double> node_time_constants_s;  // node k relaxes towards node k-1 (node 0: the case)
  double back_coupling = 0;     // a node also pulls its upstream neighbour, at this fraction of its own rate
  double self_heating_c = 0;    // steady rise of the chain's first node above the case (electronics)
  // Sensor: the node it sits on. node -1 is the case; axis may be another axis' chain.
  int sensor_axis = 0;
  int sensor_node = 0;
  double sensor_time_constant_s = 10;  // the sensor's own thermal mass
  // Drift, °/h; ΔTc = Tc - reference, rates in °C/min.
  double bias_dph = 0;
  StaticShape shape = StaticShape::polynomial;
  std::array<double, 3> polynomial{};     // per °C, °C², °C³ of ΔTc
  double step_dph = 0, step_centre_c = 0, step_width_c = 10;  // step_dph·tanh((Tc - centre)/width)
  double rate_dph = 0;            // per °C/min of dTc/dt
  double axial_gradient_dph = 0;  // per °C of (T_upstream - Tc): the gradient along the chain
  double axial_gradient_rate_dph = 0;  // per °C/min of its rate
  double radial_gain_s = 60;      // radial gradient ∇r: τr·∇r' = G·dTc/dt - ∇r
  double radial_time_constant_s = 200;
  double radial_gradient_rate_dph = 0;  // per °C/min of d∇r/dt (Shupe)
  HysteresisKind hysteresis = HysteresisKind::none;
  double hysteresis_dph = 0;
  double hysteresis_time_constant_s = 900;  // memory
  double hysteresis_rate_scale = 0.2;       // memory: r0, °C/min
  double hysteresis_width_c = 2;            // play: w
  double turn_on_dph = 0;                   // turn_on_dph·exp(-t/τ) after power-on
  double turn_on_time_constant_s = 600;
};

struct LawNoise {
  double angle_random_walk = 0.003;      // °/√h
  double bias_instability = 0.01;        // °/h
  bool flicker = false;                  // bias as a sum of Gauss-Markov processes over decades (≈ 1/f)
  double bias_correlation_time_s = 600;  // single Gauss-Markov bias otherwise
  double quantization_arcsec = 0.05;
  double temperature_noise_c = 0.005;
  double temperature_resolution_c = 0.001;
};

struct UnitLaw {
  std::uint64_t seed = 0;
  double case_time_constant_s = 300;  // the case behind the chamber air
  double case_self_heating_c = 0;     // steady rise of the case above the air when powered
  double reference_c = 20;            // ΔTc is counted from here
  double min_c = -40, max_c = 60;     // the range the unit is rated and calibrated over
  std::array<AxisLaw, 3> axes;
  LawNoise noise;

  std::string describe() const;  // one line per axis: chain, sensor, terms of the law
};

// The chamber programme: straight pieces between knots, plus an optional slow wander.
struct Setpoint {
  std::vector<double> time_s;         // knots, increasing, from 0
  std::vector<double> temperature_c;
  std::vector<double> cycle_start_s;  // where each repetition starts
  std::array<double, 3> wander_amplitude_c{};  // sum of three sines (0: none)
  std::array<double, 3> wander_period_s{3600, 5400, 8100};
  std::array<double, 3> wander_phase{};
  std::string name;

  double duration_s() const { return time_s.empty() ? 0.0 : time_s.back(); }
  double temperature(double t) const;
};

enum class ProfileKind {
  cycle,      // soak, ramp to one extreme, soak, the other, soak, back: 0.5-1.5 °C/min
  slow,       // the same at 0.2-0.7 °C/min over a narrower range
  fast,       // the same at 2-3 °C/min
  staircase,  // steps of 8-20 °C at 2-3 °C/min with 20-45 min soaks, up, down and back
  partial,    // part of the range, not returning to where it started
  wander,     // a slowly wandering setpoint (sum of sines) around the middle of the range
};
std::string to_string(ProfileKind kind);
ProfileKind parse_profile_kind(const std::string& text);  // UsageError when unknown

UnitLaw draw_unit(std::uint64_t law_seed);
// A programme within the unit's rated range; `cycles` repetitions (cycle-like kinds).
Setpoint draw_profile(ProfileKind kind, const UnitLaw& unit, std::uint64_t seed, int cycles = 1);

// A powered-on unit (every node at the air temperature when switched on) through the
// programme, sampled at rate_hz: the columns of chamber_run_columns.
ChamberRun simulate_unit(const UnitLaw& unit, const Setpoint& setpoint, std::uint64_t noise_seed,
                         double rate_hz = 1.0, const StopToken& stop = {});

// The three axes' names, as describe() and the columns of `simulate --internal-states` write them.
inline constexpr std::array<const char*, 3> kAxisNames = {"x", "y", "z"};

// The law's own regressors: the true internal states each term of an axis' drift multiplies
// (1, ΔTc, ΔTc², ΔTc³, the tanh step, dTc/dt, the axial gradient and its rate, the radial
// gradient's rate, the memory, the play, the turn-on transient), noise-free, row by row
// through the programme as simulate_unit runs it. The drift is law_coefficients · these,
// exactly. A least-squares fit of a log's gyro on them is what an identification could at
// best reach: the right structure on the true states, only the coefficients left to the
// data (bench/generalization_bench --methods oracle).
inline constexpr std::size_t kLawRegressors = 12;
std::array<std::string_view, kLawRegressors> law_regressor_names();
std::array<double, kLawRegressors> law_coefficients(const AxisLaw& law);
using LawRegressors = std::array<std::vector<std::vector<double>>, 3>;  // [axis][regressor][row]
LawRegressors law_regressors(const UnitLaw& unit, const Setpoint& setpoint, double rate_hz = 1.0);

// The same regressors rebuilt from what the run's log measures: the unit's linear thermal
// states (case, nodes, sensors, radial gradients) estimated from its three thermometers by
// a Kalman filter on the unit's own network, the chamber air modelled as a ramp whose rate
// is a random walk of intensity `air_rate_intensity` ((°C/s)²/s); the memories, plays and
// static map evaluated on the estimates. Causal: row k reads thermometer rows 0..k. Only the
// thermometers are read (not the air), the structure and every constant are the law's: a
// bound for identifications, which must rebuild the states from the same readings
// (generalization_bench --oracle-states measured). With `lookahead_s` > 0, row k reads the
// rows up to lookahead_s later too (a fixed-lag Rauch-Tung-Striebel smoother; infinity:
// every row): what a method could reach that waited that long.
// `log_likelihood` is the thermometers' under the filter, to choose the intensity by.
struct RebuiltRegressors {
  LawRegressors regressors;
  double log_likelihood = 0;
};
RebuiltRegressors law_regressors_from_thermometers(const UnitLaw& unit, const ChamberRun& run,
                                                  double air_rate_intensity, double lookahead_s = 0,
                                                  const StopToken& stop = {});

}  // namespace thermodrift::sim
