#include "thermodrift/sim/law_family.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "thermodrift/error.hpp"
#include "thermodrift/sim/standard_normal.hpp"
#include "sim/readout.hpp"

namespace thermodrift::sim {

std::vector<std::uint64_t> development_law_seeds() {
  std::vector<std::uint64_t> seeds;
  for (std::uint64_t s = 1; s <= 40; ++s) seeds.push_back(s);
  return seeds;
}

std::vector<std::uint64_t> acceptance_law_seeds() {
  std::vector<std::uint64_t> seeds;
  for (std::uint64_t s = 9001; s <= 9060; ++s) seeds.push_back(s);
  return seeds;
}

namespace {

// Draws from the engine's raw output (reproducible across standard libraries, as
// StandardNormal is).
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  double log_uniform(double low, double high) { return std::exp(uniform(std::log(low), std::log(high))); }
  bool chance(double p) { return uniform() < p; }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }
  double signed_uniform(double low, double high) { return sign() * uniform(low, high); }
  int integer(int low, int high) {  // inclusive
    return low + static_cast<int>(std::floor(uniform() * (high - low + 1)));
  }

 private:
  std::mt19937_64 engine_;
};

AxisLaw draw_axis(Draw& draw, int axis, const UnitLaw& unit) {
  AxisLaw law;
  const int nodes = draw.integer(1, 3);
  for (int k = 0; k < nodes; ++k) law.node_time_constants_s.push_back(draw.log_uniform(50, 2500));
  if (draw.chance(0.5)) law.back_coupling = draw.uniform(0.05, 0.5);
  if (draw.chance(0.5)) law.self_heating_c = draw.uniform(0.5, 3.0);
  const double site = draw.uniform();
  law.sensor_axis = axis;
  if (site < 0.25) {
    law.sensor_node = -1;  // the case
  } else if (site < 0.75) {
    law.sensor_node = draw.integer(0, nodes - 1);
  } else {
    law.sensor_axis = (axis + draw.integer(1, 2)) % 3;
    law.sensor_node = -2;  // resolved once every chain exists
  }
  law.sensor_time_constant_s = draw.log_uniform(2, 60);

  law.bias_dph = draw.uniform(-1.0, 1.0);
  if (draw.chance(0.6)) {
    law.shape = StaticShape::polynomial;
    law.polynomial = {draw.signed_uniform(0.005, 0.05), draw.signed_uniform(0.0, 8e-4),
                      draw.chance(0.5) ? draw.signed_uniform(0.0, 1.5e-5) : 0.0};
  } else {
    law.shape = StaticShape::tanh_step;
    law.polynomial = {draw.signed_uniform(0.0, 0.03), 0.0, 0.0};
    law.step_dph = draw.signed_uniform(0.3, 1.5);
    law.step_centre_c = draw.uniform(unit.min_c + 20, unit.max_c - 20);
    law.step_width_c = draw.uniform(8, 30);
  }
  law.rate_dph = draw.signed_uniform(0.2, 2.5);
  if (draw.chance(0.5)) law.axial_gradient_dph = draw.signed_uniform(0.02, 0.2);
  if (draw.chance(0.5)) law.axial_gradient_rate_dph = draw.signed_uniform(0.5, 3.0);
  if (draw.chance(0.7)) {
    law.radial_gain_s = draw.log_uniform(20, 150);
    law.radial_time_constant_s = draw.log_uniform(60, 600);
    law.radial_gradient_rate_dph = draw.signed_uniform(0.5, 4.0);
  }
  const double hysteresis = draw.uniform();
  if (hysteresis < 0.45) {
    law.hysteresis = HysteresisKind::memory;
    law.hysteresis_time_constant_s = draw.log_uniform(200, 3000);
    law.hysteresis_rate_scale = draw.log_uniform(0.05, 0.5);
  } else if (hysteresis < 0.75) {
    law.hysteresis = HysteresisKind::play;
    law.hysteresis_width_c = draw.uniform(0.5, 5.0);
  }
  if (law.hysteresis != HysteresisKind::none) law.hysteresis_dph = draw.signed_uniform(0.05, 0.5);
  if (draw.chance(0.5)) {
    law.turn_on_dph = draw.signed_uniform(0.05, 0.5);
    law.turn_on_time_constant_s = draw.log_uniform(150, 900);
  }
  return law;
}

}  // namespace

UnitLaw draw_unit(std::uint64_t law_seed) {
  Draw draw(derive_seed(law_seed, 0x1a3));
  UnitLaw unit;
  unit.seed = law_seed;
  unit.min_c = draw.uniform(-45, -25);
  unit.max_c = draw.uniform(50, 70);
  unit.reference_c = draw.uniform(15, 25);
  unit.case_time_constant_s = draw.log_uniform(50, 800);
  if (draw.chance(0.6)) unit.case_self_heating_c = draw.uniform(0.5, 5.0);
  for (int a = 0; a < 3; ++a) unit.axes[static_cast<std::size_t>(a)] = draw_axis(draw, a, unit);
  for (auto& axis : unit.axes) {
    if (axis.sensor_node == -2) {
      const auto other = unit.axes[static_cast<std::size_t>(axis.sensor_axis)].node_time_constants_s.size();
      axis.sensor_node = draw.integer(0, static_cast<int>(other) - 1);
    }
  }
  LawNoise& noise = unit.noise;
  noise.angle_random_walk = draw.log_uniform(0.0015, 0.008);
  noise.bias_instability = draw.log_uniform(0.004, 0.02);
  noise.flicker = draw.chance(0.5);
  noise.bias_correlation_time_s = draw.log_uniform(100, 3000);
  noise.quantization_arcsec = draw.chance(0.3) ? 0.0 : draw.uniform(0.01, 0.1);
  noise.temperature_noise_c = draw.log_uniform(0.001, 0.02);
  static constexpr std::array<double, 4> resolutions = {0.0001, 0.001, 0.01, 0.0625};
  noise.temperature_resolution_c = resolutions[static_cast<std::size_t>(draw.integer(0, 3))];
  return unit;
}

namespace {

// The hysteresis' own constants: a memory's time constant and rate scale, a play's half-width.
std::string hysteresis_detail(const AxisLaw& axis) {
  switch (axis.hysteresis) {
    case HysteresisKind::memory:
      return fmt::format(" (τ {:.0f} s, R0 {:.2f} °C/min)", axis.hysteresis_time_constant_s, axis.hysteresis_rate_scale);
    case HysteresisKind::play: return fmt::format(" (W {:.2f} °C)", axis.hysteresis_width_c);
    case HysteresisKind::none: break;
  }
  return {};
}

}  // namespace

std::string UnitLaw::describe() const {
  std::string text = fmt::format("law {}: range {:.0f}..{:.0f} °C, case τ {:.0f} s (+{:.1f} °C powered); noise ARW {:.4f} °/√h, "
                                 "BI {:.4f} °/h {}, temp noise {:.3f} °C res {:g} °C\n",
                                 seed, min_c, max_c, case_time_constant_s, case_self_heating_c, noise.angle_random_walk,
                                 noise.bias_instability, noise.flicker ? "flicker" : "Gauss-Markov",
                                 noise.temperature_noise_c, noise.temperature_resolution_c);
  static constexpr std::array<const char*, 3> hysteresis_names = {"none", "memory", "play"};
  for (std::size_t a = 0; a < 3; ++a) {
    const AxisLaw& axis = axes[a];
    std::string chain;
    for (double tau : axis.node_time_constants_s) chain += fmt::format("{}{:.0f}", chain.empty() ? "" : "→", tau);
    text += fmt::format("  {}: chain {} s (back {:.2f}, +{:.1f} °C), sensor on {}{} (τ {:.0f} s); {} a=({:.3g},{:.3g},{:.3g}) "
                        "step {:.2f}; rate {:.2f}; axial {:.3f}/{:.2f}; radial {:.2f} (G {:.0f} s, τ {:.0f} s); "
                        "hysteresis {} {:.2f}{}; turn-on {:.2f} ({:.0f} s)\n",
                        kAxisNames[a], chain, axis.back_coupling, axis.self_heating_c,
                        axis.sensor_node < 0 ? "case" : fmt::format("{} node {}", kAxisNames[static_cast<std::size_t>(axis.sensor_axis)], axis.sensor_node + 1),
                        "", axis.sensor_time_constant_s, axis.shape == StaticShape::polynomial ? "poly" : "tanh",
                        axis.polynomial[0], axis.polynomial[1], axis.polynomial[2], axis.step_dph, axis.rate_dph,
                        axis.axial_gradient_dph, axis.axial_gradient_rate_dph, axis.radial_gradient_rate_dph,
                        axis.radial_gain_s, axis.radial_time_constant_s,
                        hysteresis_names[static_cast<std::size_t>(axis.hysteresis)], axis.hysteresis_dph, hysteresis_detail(axis),
                        axis.turn_on_dph, axis.turn_on_time_constant_s);
  }
  return text;
}

// ---------------------------------------------------------------- profiles

double Setpoint::temperature(double t) const {
  double value = 0;
  if (time_s.empty()) return value;
  if (t <= time_s.front()) {
    value = temperature_c.front();
  } else if (t >= time_s.back()) {
    value = temperature_c.back();
  } else {
    const auto upper = std::upper_bound(time_s.begin(), time_s.end(), t);
    const auto k = static_cast<std::size_t>(upper - time_s.begin());
    const double fraction = (t - time_s[k - 1]) / (time_s[k] - time_s[k - 1]);
    value = temperature_c[k - 1] + fraction * (temperature_c[k] - temperature_c[k - 1]);
  }
  for (std::size_t i = 0; i < 3; ++i) {
    if (wander_amplitude_c[i] == 0) continue;
    // Sines that start at zero, so the programme starts at its first knot.
    const double phase = 2 * std::numbers::pi * t / wander_period_s[i] + wander_phase[i];
    value += wander_amplitude_c[i] * (std::sin(phase) - std::sin(wander_phase[i]));
  }
  return value;
}

std::string to_string(ProfileKind kind) {
  switch (kind) {
    case ProfileKind::cycle: return "cycle";
    case ProfileKind::slow: return "slow";
    case ProfileKind::fast: return "fast";
    case ProfileKind::staircase: return "staircase";
    case ProfileKind::partial: return "partial";
    case ProfileKind::wander: return "wander";
  }
  return "cycle";
}

ProfileKind parse_profile_kind(const std::string& text) {
  for (ProfileKind kind : {ProfileKind::cycle, ProfileKind::slow, ProfileKind::fast, ProfileKind::staircase,
                           ProfileKind::partial, ProfileKind::wander}) {
    if (to_string(kind) == text) return kind;
  }
  throw UsageError(fmt::format("unknown profile '{}' (expected cycle, slow, fast, staircase, partial or wander)", text));
}

namespace {

class ProgrammeBuilder {
 public:
  explicit ProgrammeBuilder(double start_c) {
    setpoint_.time_s.push_back(0);
    setpoint_.temperature_c.push_back(start_c);
  }
  double now_c() const { return setpoint_.temperature_c.back(); }
  void ramp(double target_c, double rate_c_per_min) {
    const double duration = std::abs(target_c - now_c()) / rate_c_per_min * 60.0;
    // Rounding leaves the staircase's last step a few ulp short of the start: no knot for it
    // (it would repeat the previous knot's time).
    if (duration < 1e-6) return;
    add(duration, target_c);
  }
  void soak(double minutes) {
    if (minutes > 0) add(minutes * 60.0, now_c());
  }
  void mark_cycle() { setpoint_.cycle_start_s.push_back(setpoint_.time_s.back()); }
  Setpoint take(std::string name) {
    setpoint_.name = std::move(name);
    if (setpoint_.cycle_start_s.empty()) setpoint_.cycle_start_s.push_back(0);
    return std::move(setpoint_);
  }

 private:
  void add(double seconds, double target_c) {
    setpoint_.time_s.push_back(setpoint_.time_s.back() + seconds);
    setpoint_.temperature_c.push_back(target_c);
  }
  Setpoint setpoint_;
};

}  // namespace

Setpoint draw_profile(ProfileKind kind, const UnitLaw& unit, std::uint64_t seed, int cycles) {
  if (cycles < 1 || cycles > 100) throw UsageError("profile cycles must be in 1..100");
  Draw draw(derive_seed(seed, 0x77 + static_cast<std::uint64_t>(kind)));
  const double span = unit.max_c - unit.min_c;
  const double start = std::clamp(draw.uniform(15, 25), unit.min_c, unit.max_c);
  ProgrammeBuilder programme(start);
  const std::string name = to_string(kind);
  switch (kind) {
    case ProfileKind::cycle:
    case ProfileKind::slow:
    case ProfileKind::fast: {
      double low = unit.min_c, high = unit.max_c, rate = draw.uniform(0.5, 1.5);
      double soak = draw.uniform(30, 90);
      if (kind == ProfileKind::slow) {
        rate = draw.uniform(0.2, 0.7);
        low = std::min(start - 5, unit.min_c + draw.uniform(0, 0.3) * span);
        high = std::max(start + 5, unit.max_c - draw.uniform(0, 0.3) * span);
        soak = draw.uniform(20, 60);
      } else if (kind == ProfileKind::fast) {
        rate = draw.uniform(2, 3);
        soak = draw.uniform(20, 60);
      }
      const bool heat_first = draw.chance(0.5);
      for (int c = 0; c < cycles; ++c) {
        programme.mark_cycle();
        programme.soak(soak);
        programme.ramp(heat_first ? high : low, rate);
        programme.soak(soak);
        programme.ramp(heat_first ? low : high, rate);
        programme.soak(soak);
        programme.ramp(start, rate);
      }
      break;
    }
    case ProfileKind::staircase: {
      const double step = draw.uniform(8, 20), rate = draw.uniform(2, 3), soak = draw.uniform(20, 45);
      for (int c = 0; c < cycles; ++c) {
        programme.mark_cycle();
        programme.soak(soak);
        while (programme.now_c() + step <= unit.max_c) { programme.ramp(programme.now_c() + step, rate); programme.soak(soak); }
        while (programme.now_c() - step >= unit.min_c) { programme.ramp(programme.now_c() - step, rate); programme.soak(soak); }
        while (programme.now_c() + step <= start) { programme.ramp(programme.now_c() + step, rate); programme.soak(soak); }
        programme.ramp(start, rate);
      }
      break;
    }
    case ProfileKind::partial: {
      for (int c = 0; c < cycles; ++c) {
        programme.mark_cycle();
        const double rate = draw.uniform(0.5, 1.5);
        const double high = draw.uniform(std::max(start + 10, unit.min_c + 0.5 * span), unit.max_c);
        const double low = draw.uniform(unit.min_c, std::min(start - 10, unit.min_c + 0.5 * span));
        programme.soak(draw.uniform(20, 60));
        programme.ramp(draw.chance(0.5) ? high : low, rate);
        programme.soak(draw.uniform(10, 60));
        programme.ramp(draw.uniform(low, high), rate);
        programme.soak(draw.uniform(30, 90));
      }
      break;
    }
    case ProfileKind::wander: {
      programme.mark_cycle();
      Setpoint setpoint = programme.take(name);
      const double middle = 0.5 * (unit.min_c + unit.max_c);
      setpoint.temperature_c.front() = middle;
      const double hours = draw.uniform(6, 8) * cycles;
      setpoint.time_s.push_back(hours * 3600);
      setpoint.temperature_c.push_back(middle);
      // Three sines whose peak sum stays within the range around its middle.
      const double budget = 0.45 * span;
      double used = 0;
      for (std::size_t i = 0; i < 3; ++i) {
        setpoint.wander_period_s[i] = draw.uniform(0.7, 4.0) * 3600;
        setpoint.wander_phase[i] = draw.uniform(0, 2 * std::numbers::pi);
        setpoint.wander_amplitude_c[i] = draw.uniform(0.15, 0.33) * budget;
        used += 2 * setpoint.wander_amplitude_c[i];
      }
      if (used > budget) {
        for (auto& amplitude : setpoint.wander_amplitude_c) amplitude *= budget / used;
      }
      return setpoint;
    }
  }
  return programme.take(name);
}

// ---------------------------------------------------------------- the unit in time

std::array<std::string_view, kLawRegressors> law_regressor_names() {
  return {"bias", "dTc", "dTc^2", "dTc^3", "step", "coil_rate", "axial_gradient", "axial_gradient_rate",
          "radial_gradient_rate", "memory", "play", "turn_on"};
}

std::array<double, kLawRegressors> law_coefficients(const AxisLaw& law) {
  return {law.bias_dph,
          law.polynomial[0],
          law.polynomial[1],
          law.polynomial[2],
          law.step_dph,
          law.rate_dph,
          law.axial_gradient_dph,
          law.axial_gradient_rate_dph,
          law.radial_gradient_rate_dph,
          law.hysteresis_dph,
          law.hysteresis_dph,
          law.turn_on_dph};
}

namespace {

// The thermal state of the whole unit: the case, each axis' chain, each sensor, and the
// filtered states of the drift laws. Continuous parts advance by RK4 in substeps of the
// sample interval; the play operator is applied after each substep.
class UnitPhysics {
 public:
  explicit UnitPhysics(const UnitLaw& unit, double start_c)
      : unit_(unit), fastest_rate_bound_per_s_(fastest_rate_bound(unit)) {
    std::size_t index = 1;  // 0: the case
    for (const auto& axis : unit.axes) {
      offsets_.push_back(index);
      index += axis.node_time_constants_s.size();
    }
    sensor_ = index;  // then per axis: sensor, radial gradient, memory
    state_.assign(index + 9, start_c);
    for (std::size_t a = 0; a < 3; ++a) {
      state_[radial(a)] = 0;
      state_[memory(a)] = 0;
      play_[a] = start_c;
    }
  }

  // Advances dt in substeps short enough for RK4: with h·|λ| <= 1 for the fastest mode it
  // is stable (the limit is 2.78) and accurate, whatever the sample rate. At 1 Hz and above
  // the drawn time constants (>= 2 s) need one substep.
  void step(double t, double dt, const Setpoint& setpoint) {
    const int substeps = std::max(1, static_cast<int>(std::ceil(dt * fastest_rate_bound_per_s_ - 1e-12)));
    const double h = dt / substeps;
    for (int s = 0; s < substeps; ++s) rk4_step(t + s * h, h, setpoint);
  }

  double sensor_c(std::size_t a) const { return state_[sensor_ + 3 * a]; }

  // The law's regressors for axis a at time t (s since power-on) with the air at `air_c`:
  // the true internal states each term of its drift multiplies (law_regressor_names).
  std::array<double, kLawRegressors> regressors(std::size_t a, double t, double air_c) const {
    std::vector<double> rate(state_.size());
    derivative(state_, air_c, rate);
    const AxisLaw& law = unit_.axes[a];
    const std::size_t coil = coil_index(a);
    const double tc = state_[coil];
    const double delta = tc - unit_.reference_c;
    const double coil_rate = rate[coil] * 60.0;  // °C/min
    const std::size_t upstream = law.node_time_constants_s.size() == 1 ? 0 : coil - 1;
    const double upstream_c = state_[upstream] + (upstream == 0 ? law.self_heating_c * powered_ : 0.0);
    return {1.0,
            delta,
            delta * delta,
            delta * delta * delta,
            law.shape == StaticShape::tanh_step ? std::tanh((tc - law.step_centre_c) / law.step_width_c) : 0.0,
            coil_rate,
            upstream_c - tc,
            rate[upstream] * 60.0 - coil_rate,
            rate[radial(a)] * 60.0,
            law.hysteresis == HysteresisKind::memory ? state_[memory(a)] : 0.0,
            law.hysteresis == HysteresisKind::play ? (tc - play_[a]) / law.hysteresis_width_c : 0.0,
            std::exp(-t / law.turn_on_time_constant_s)};
  }

  // The network's linear part, probed from derivative(): d(state)/dt = jacobian·state +
  // air_gain·air + drive (the self-heating). Exact on every row but the memories' (a tanh of
  // the coil's rate), which linear_states() leaves out.
  void linear_part(Eigen::MatrixXd& jacobian, Eigen::VectorXd& air_gain, Eigen::VectorXd& drive) const {
    const std::size_t n = state_.size();
    std::vector<double> x(n, 0.0), dx(n);
    derivative(x, 0.0, dx);
    drive = Eigen::Map<const Eigen::VectorXd>(dx.data(), static_cast<Eigen::Index>(n));
    derivative(x, 1.0, dx);
    air_gain = Eigen::Map<const Eigen::VectorXd>(dx.data(), static_cast<Eigen::Index>(n)) - drive;
    jacobian.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    for (std::size_t j = 0; j < n; ++j) {
      x[j] = 1.0;
      derivative(x, 0.0, dx);
      x[j] = 0.0;
      jacobian.col(static_cast<Eigen::Index>(j)) =
          Eigen::Map<const Eigen::VectorXd>(dx.data(), static_cast<Eigen::Index>(n)) - drive;
    }
  }
  std::vector<std::size_t> linear_states() const {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < state_.size(); ++i) {
      if (i < sensor_ || (i - sensor_) % 3 != 2) out.push_back(i);
    }
    return out;
  }
  std::size_t sensor_index(std::size_t a) const { return sensor_ + 3 * a; }
  // The case, the nodes and the sensors; the rest are the radial gradients and memories.
  bool is_temperature(std::size_t i) const { return i < sensor_ || (i - sensor_) % 3 == 0; }

  // Sets the network's linear states (linear_states() order) to an estimate, and advances
  // the memories and plays over dt on it, the coil's rate held: what the law's nonlinear
  // states would be were the estimate the truth.
  void follow(const std::vector<std::size_t>& linear, const Eigen::VectorXd& estimate, double air_c, double dt) {
    for (std::size_t i = 0; i < linear.size(); ++i) state_[linear[i]] = estimate[static_cast<Eigen::Index>(i)];
    std::vector<double> rate(state_.size());
    derivative(state_, air_c, rate);
    for (std::size_t a = 0; a < 3; ++a) {
      const AxisLaw& law = unit_.axes[a];
      const double coil = state_[coil_index(a)];
      if (law.hysteresis == HysteresisKind::play) {
        play_[a] = std::clamp(play_[a], coil - law.hysteresis_width_c, coil + law.hysteresis_width_c);
      }
      const double target = std::tanh(rate[coil_index(a)] * 60.0 / law.hysteresis_rate_scale);
      state_[memory(a)] = target + (state_[memory(a)] - target) * std::exp(-dt / law.hysteresis_time_constant_s);
    }
  }

  // True drift (°/h) of axis a: the law's coefficients on its regressors.
  double drift_dph(std::size_t a, double t, double air_c) const {
    const auto x = regressors(a, t, air_c);
    const auto c = law_coefficients(unit_.axes[a]);
    double drift = 0;
    for (std::size_t k = 0; k < kLawRegressors; ++k) drift += c[k] * x[k];
    return drift;
  }

 private:
  std::size_t coil_index(std::size_t a) const { return offsets_[a] + unit_.axes[a].node_time_constants_s.size() - 1; }
  std::size_t radial(std::size_t a) const { return sensor_ + 3 * a + 1; }
  std::size_t memory(std::size_t a) const { return sensor_ + 3 * a + 2; }
  std::size_t site(std::size_t a) const {
    const AxisLaw& law = unit_.axes[a];
    if (law.sensor_node < 0) return 0;
    return offsets_[static_cast<std::size_t>(law.sensor_axis)] + static_cast<std::size_t>(law.sensor_node);
  }

  void rk4_step(double t, double dt, const Setpoint& setpoint) {
    const std::size_t n = state_.size();
    std::vector<double> k1(n), k2(n), k3(n), k4(n), x(n);
    derivative(state_, setpoint.temperature(t), k1);
    for (std::size_t i = 0; i < n; ++i) x[i] = state_[i] + 0.5 * dt * k1[i];
    derivative(x, setpoint.temperature(t + 0.5 * dt), k2);
    for (std::size_t i = 0; i < n; ++i) x[i] = state_[i] + 0.5 * dt * k2[i];
    derivative(x, setpoint.temperature(t + 0.5 * dt), k3);
    for (std::size_t i = 0; i < n; ++i) x[i] = state_[i] + dt * k3[i];
    derivative(x, setpoint.temperature(t + dt), k4);
    for (std::size_t i = 0; i < n; ++i) state_[i] += dt / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    for (std::size_t a = 0; a < 3; ++a) {
      const AxisLaw& law = unit_.axes[a];
      if (law.hysteresis != HysteresisKind::play) continue;
      const double coil = state_[coil_index(a)];
      play_[a] = std::clamp(play_[a], coil - law.hysteresis_width_c, coil + law.hysteresis_width_c);
    }
  }

  // Gershgorin: every eigenvalue of the (linearised) network lies within the largest
  // absolute row sum of its Jacobian. A lag row relaxing at rate r towards its neighbours
  // sums to 2r; the radial and memory rows also read the coil's rate (Tup - Tc)/τn.
  static double fastest_rate_bound(const UnitLaw& unit) {
    double bound = 2.0 / unit.case_time_constant_s;
    for (const AxisLaw& law : unit.axes) {
      const auto& taus = law.node_time_constants_s;
      for (std::size_t k = 0; k < taus.size(); ++k) {
        const double pulled = k + 1 < taus.size() ? law.back_coupling / taus[k + 1] : 0.0;
        bound = std::max(bound, 2.0 * (1.0 / taus[k] + pulled));
      }
      const double coil_rate_gain = 2.0 / taus.back();  // |∂(dTc/dt)/∂x| summed over Tup and Tc
      const double radial = (1.0 + law.radial_gain_s * coil_rate_gain) / law.radial_time_constant_s;
      const double memory = (1.0 + 60.0 / law.hysteresis_rate_scale * coil_rate_gain) / law.hysteresis_time_constant_s;
      bound = std::max({bound, 2.0 / law.sensor_time_constant_s, radial, memory});
    }
    return bound;
  }

  void derivative(const std::vector<double>& x, double air_c, std::vector<double>& dx) const {
    std::fill(dx.begin(), dx.end(), 0.0);
    dx[0] = (air_c + unit_.case_self_heating_c * powered_ - x[0]) / unit_.case_time_constant_s;
    for (std::size_t a = 0; a < 3; ++a) {
      const AxisLaw& law = unit_.axes[a];
      const auto& taus = law.node_time_constants_s;
      for (std::size_t k = 0; k < taus.size(); ++k) {
        const std::size_t i = offsets_[a] + k;
        const double upstream = k == 0 ? x[0] + law.self_heating_c * powered_ : x[i - 1];
        dx[i] += (upstream - x[i]) / taus[k];
        if (k > 0) dx[i - 1] += law.back_coupling * (x[i] - x[i - 1]) / taus[k];
      }
    }
    for (std::size_t a = 0; a < 3; ++a) {
      const AxisLaw& law = unit_.axes[a];
      const std::size_t coil = coil_index(a);
      dx[sensor_ + 3 * a] = (x[site(a)] - x[sensor_ + 3 * a]) / law.sensor_time_constant_s;
      const double coil_rate = dx[coil];  // final: nothing adds to the coil's rate after the chain loop
      dx[radial(a)] = (law.radial_gain_s * coil_rate - x[radial(a)]) / law.radial_time_constant_s;
      dx[memory(a)] = (std::tanh(coil_rate * 60.0 / law.hysteresis_rate_scale) - x[memory(a)]) /
                      law.hysteresis_time_constant_s;
    }
  }

  const UnitLaw& unit_;
  double fastest_rate_bound_per_s_;
  std::vector<std::size_t> offsets_;
  std::size_t sensor_ = 0;
  std::vector<double> state_;
  std::array<double, 3> play_{};
  double powered_ = 1.0;
};

// Rate noise of one axis: white (ARW), bias instability (one Gauss-Markov process, or four
// a decade apart for a flicker-like floor), and a pulse output's quantization.
class LawAxisNoise {
 public:
  LawAxisNoise(const LawNoise& noise, double dt, std::uint64_t seed, std::uint64_t axis)
      : white_std_(noise.angle_random_walk * 60.0 / std::sqrt(dt)),
        pulses_(noise.quantization_arcsec, dt),
        white_(derive_seed(seed, 10 * axis)),
        bias_(derive_seed(seed, 10 * axis + 1)),
        thermometer_(derive_seed(seed, 10 * axis + 2)),
        temperature_noise_(noise.temperature_noise_c),
        resolution_(noise.temperature_resolution_c) {
    // Gauss-Markov of stationary std σ has an Allan-deviation peak 0.6174·σ; B's floor is 0.664·B.
    // Four processes a decade apart, each of variance s², have an Allan variance of 1.44-1.58
    // times one process' peak (0.3811·s²) between 100 s and 2·10⁴ s, 1.55 at the peaks: with
    // s² = σ²/1.55 their floor is B's.
    const double sigma = noise.bias_instability * 0.6643 / 0.6174;
    if (noise.flicker) {
      for (double tau : {30.0, 300.0, 3000.0, 30000.0}) processes_.push_back({std::exp(-dt / tau), sigma / std::sqrt(1.55), 0});
    } else {
      processes_.push_back({std::exp(-dt / noise.bias_correlation_time_s), sigma, 0});
    }
    for (auto& p : processes_) p.value = p.sigma * bias_();
  }

  double gyro_dph(double drift) {
    double rate = drift + white_std_ * white_();
    for (auto& p : processes_) {
      rate += p.value;
      p.value = p.phi * p.value + p.sigma * std::sqrt(1 - p.phi * p.phi) * bias_();
    }
    return pulses_(rate);
  }

  double temperature_c(double true_c) {
    const double reading = true_c + temperature_noise_ * thermometer_();
    return at_resolution(reading, resolution_);
  }

 private:
  struct Process {
    double phi, sigma, value;
  };
  double white_std_;
  PulseOutput pulses_;
  StandardNormal white_, bias_, thermometer_;
  double temperature_noise_, resolution_;
  std::vector<Process> processes_;
};

}  // namespace

namespace {

std::size_t programme_rows(const Setpoint& setpoint, double rate_hz) {
  if (!(rate_hz > 0 && rate_hz <= 100)) throw UsageError("the law family simulates at 0..100 Hz");
  if (setpoint.time_s.size() < 2) throw UsageError("a programme needs at least two knots");
  return static_cast<std::size_t>(std::floor(setpoint.duration_s() * rate_hz + 1e-9)) + 1;
}

}  // namespace

ChamberRun simulate_unit(const UnitLaw& unit, const Setpoint& setpoint, std::uint64_t noise_seed, double rate_hz,
                         const StopToken& stop) {
  const std::size_t rows = programme_rows(setpoint, rate_hz);
  const double dt = 1.0 / rate_hz;
  ChamberRun run;
  run.rate_hz = rate_hz;
  run.cycle_start_s = setpoint.cycle_start_s;
  for (std::string_view name : chamber_run_columns) run.column_names.emplace_back(name);
  run.columns.assign(run.column_names.size(), std::vector<double>(rows));

  UnitPhysics physics(unit, setpoint.temperature(0));
  std::vector<LawAxisNoise> noise;
  for (std::uint64_t a = 0; a < 3; ++a) noise.emplace_back(unit.noise, dt, noise_seed, a);
  for (std::size_t k = 0; k < rows; ++k) {
    if (k % 4096 == 0) stop.throw_if_requested("simulation");
    const double t = static_cast<double>(k) * dt;
    const double air = setpoint.temperature(t);
    run.columns[0][k] = t;
    run.columns[1][k] = air;
    for (std::size_t a = 0; a < 3; ++a) {
      const double drift = physics.drift_dph(a, t, air);
      run.columns[2 + a][k] = noise[a].temperature_c(physics.sensor_c(a));
      run.columns[5 + a][k] = noise[a].gyro_dph(drift);
      run.columns[8 + a][k] = drift;
    }
    physics.step(t, dt, setpoint);
  }
  return run;
}

LawRegressors law_regressors(const UnitLaw& unit, const Setpoint& setpoint, double rate_hz) {
  const std::size_t rows = programme_rows(setpoint, rate_hz);
  const double dt = 1.0 / rate_hz;
  LawRegressors out;
  for (auto& axis : out) axis.assign(kLawRegressors, std::vector<double>(rows));
  UnitPhysics physics(unit, setpoint.temperature(0));
  for (std::size_t k = 0; k < rows; ++k) {
    const double t = static_cast<double>(k) * dt;
    const double air = setpoint.temperature(t);
    for (std::size_t a = 0; a < 3; ++a) {
      const auto x = physics.regressors(a, t, air);
      for (std::size_t j = 0; j < kLawRegressors; ++j) out[a][j][k] = x[j];
    }
    physics.step(t, dt, setpoint);
  }
  return out;
}

RebuiltRegressors law_regressors_from_thermometers(const UnitLaw& unit, const ChamberRun& run,
                                                  double air_rate_intensity, double lookahead_s, const StopToken& stop) {
  const std::size_t rows = run.rows();
  if (rows == 0) throw UsageError("no rows to rebuild the law's states from");
  const double dt = 1.0 / run.rate_hz;
  const std::vector<double>& time = run.column(time_column);
  std::array<const std::vector<double>*, 3> thermometers{};
  for (std::size_t a = 0; a < 3; ++a) thermometers[a] = &run.column(temperature_columns[a]);

  UnitPhysics physics(unit, (*thermometers[0])[0]);
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd air_gain, drive;
  physics.linear_part(jacobian, air_gain, drive);
  const std::vector<std::size_t> linear = physics.linear_states();
  // The filter's state: the air, its rate (a random walk of intensity q), the network's
  // linear states; its continuous model F·s + d, discretized exactly over dt with a
  // constant appended (the drive), its noise by Van Loan's method.
  const auto m = static_cast<Eigen::Index>(linear.size() + 2);
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(m);
  f(0, 1) = 1.0;
  for (Eigen::Index i = 0; i + 2 < m; ++i) {
    const auto li = static_cast<Eigen::Index>(linear[static_cast<std::size_t>(i)]);
    f(i + 2, 0) = air_gain[li];
    d[i + 2] = drive[li];
    for (Eigen::Index j = 0; j + 2 < m; ++j) {
      f(i + 2, j + 2) = jacobian(li, static_cast<Eigen::Index>(linear[static_cast<std::size_t>(j)]));
    }
  }
  Eigen::MatrixXd augmented = Eigen::MatrixXd::Zero(m + 1, m + 1);
  augmented.topLeftCorner(m, m) = f * dt;
  augmented.topRightCorner(m, 1) = d * dt;
  const Eigen::MatrixXd step = augmented.exp();
  const Eigen::MatrixXd phi = step.topLeftCorner(m, m);
  const Eigen::VectorXd offset = step.topRightCorner(m, 1);
  Eigen::MatrixXd van_loan = Eigen::MatrixXd::Zero(2 * m, 2 * m);
  van_loan.topLeftCorner(m, m) = -f * dt;
  van_loan(1, m + 1) = air_rate_intensity * dt;
  van_loan.bottomRightCorner(m, m) = f.transpose() * dt;
  const Eigen::MatrixXd vl = van_loan.exp();
  Eigen::MatrixXd q = vl.bottomRightCorner(m, m).transpose() * vl.topRightCorner(m, m);
  q = 0.5 * (q + q.transpose());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(3, m);
  for (std::size_t a = 0; a < 3; ++a) {
    const auto found = std::find(linear.begin(), linear.end(), physics.sensor_index(a));
    h(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(found - linear.begin()) + 2) = 1.0;
  }
  const double resolution = unit.noise.temperature_resolution_c;
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(3, 3) *
                            (unit.noise.temperature_noise_c * unit.noise.temperature_noise_c + resolution * resolution / 12);

  // Switched on in equilibrium: every temperature the same, not known; no rates.
  const double start = ((*thermometers[0])[0] + (*thermometers[1])[0] + (*thermometers[2])[0]) / 3;
  Eigen::VectorXd s = Eigen::VectorXd::Zero(m);
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(m, m) * 1e-6;
  Eigen::VectorXd common = Eigen::VectorXd::Zero(m);
  s[0] = start;
  common[0] = 1;
  for (Eigen::Index i = 2; i < m; ++i) {
    if (physics.is_temperature(linear[static_cast<std::size_t>(i - 2)])) {  // radial gradients start at 0
      s[i] = start;
      common[i] = 1;
    }
  }
  p += common * common.transpose();
  p(1, 1) += 1.0 / 3600.0;  // (1 °C/min)²

  RebuiltRegressors out;
  for (auto& axis : out.regressors) axis.assign(kLawRegressors, std::vector<double>(rows));
  const auto evaluate_row = [&](std::size_t k, const Eigen::VectorXd& estimate) {
    physics.follow(linear, estimate.tail(m - 2), estimate[0], k > 0 ? dt : 0.0);
    for (std::size_t a = 0; a < 3; ++a) {
      const auto x = physics.regressors(a, time[k], estimate[0]);
      for (std::size_t j = 0; j < kLawRegressors; ++j) out.regressors[a][j][k] = x[j];
    }
  };
  // With a look-ahead, each row's filtered estimate and Rauch-Tung-Striebel gain are kept
  // for the passes backwards.
  const std::size_t ahead =
      std::isinf(lookahead_s) ? rows : static_cast<std::size_t>(std::llround(lookahead_s * run.rate_hz));
  std::vector<Eigen::VectorXd> filtered;
  std::vector<Eigen::MatrixXd> gains;
  Eigen::Vector3d y;
  for (std::size_t k = 0; k < rows; ++k) {
    if (k % 4096 == 0) stop.throw_if_requested("rebuilding the law's states");
    if (k > 0) {
      s = phi * s + offset;
      const Eigen::MatrixXd predicted = phi * p * phi.transpose() + q;
      if (ahead > 0) {
        // The process noise drives only the air's rate, so a predicted covariance is close
        // to singular (states tied to each other by the network): a least-squares solve.
        gains.push_back(predicted.completeOrthogonalDecomposition().solve(phi * p).transpose());
      }
      p = predicted;
    }
    for (std::size_t a = 0; a < 3; ++a) y[static_cast<Eigen::Index>(a)] = (*thermometers[a])[k];
    const Eigen::Vector3d innovation = y - h * s;
    const Eigen::Matrix3d covariance = h * p * h.transpose() + r;
    const Eigen::LLT<Eigen::Matrix3d> llt(covariance);
    const Eigen::MatrixXd gain = llt.solve(h * p).transpose();
    s += gain * innovation;
    // Joseph's form: stays positive definite where the air's rate hardly moves.
    const Eigen::MatrixXd keep = Eigen::MatrixXd::Identity(m, m) - gain * h;
    p = keep * p * keep.transpose() + gain * r * gain.transpose();
    p = 0.5 * (p + p.transpose());
    const Eigen::Matrix3d l = llt.matrixL();
    out.log_likelihood -= 0.5 * (innovation.dot(llt.solve(innovation)) +
                                 2 * l.diagonal().array().log().sum() + 3 * std::log(2 * std::numbers::pi));
    if (ahead > 0) filtered.push_back(s);
    else evaluate_row(k, s);
  }
  // Row j's estimate from the rows after it, given row j + 1's from the same rows.
  const auto back = [&](std::size_t j, const Eigen::VectorXd& later) -> Eigen::VectorXd {
    return filtered[j] + gains[j] * (later - (phi * filtered[j] + offset));
  };
  if (ahead >= rows) {  // every row: one pass backwards
    for (std::size_t k = rows - 1; k-- > 0;) filtered[k] = back(k, filtered[k + 1]);
    for (std::size_t k = 0; k < rows; ++k) evaluate_row(k, filtered[k]);
  } else if (ahead > 0) {  // row k from rows up to k + ahead: a pass back from there for each
    for (std::size_t k = 0; k < rows; ++k) {
      if (k % 4096 == 0) stop.throw_if_requested("rebuilding the law's states");
      std::size_t j = std::min(k + ahead, rows - 1);
      Eigen::VectorXd estimate = filtered[j];
      while (j > k) {
        --j;
        estimate = back(j, estimate);
      }
      evaluate_row(k, estimate);
    }
  }
  return out;
}

}  // namespace thermodrift::sim
