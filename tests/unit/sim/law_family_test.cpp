// The law family (docs/simulator.md, "The law family"): the seed lists, reproducibility,
// the documented ranges of every draw and programme, the physics against closed forms on a
// hand-built unit, and the scale of the noise.
#include "thermodrift/sim/law_family.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "thermodrift/error.hpp"

namespace thermodrift::sim {
namespace {

constexpr std::array<ProfileKind, 6> kAllKinds = {ProfileKind::cycle,     ProfileKind::slow,    ProfileKind::fast,
                                                  ProfileKind::staircase, ProfileKind::partial, ProfileKind::wander};

bool in_range(double value, double low, double high) { return value >= low && value <= high; }
bool zero_or_in_range(double value, double low, double high) { return value == 0 || in_range(value, low, high); }
bool magnitude_in_range(double value, double low, double high) { return in_range(std::abs(value), low, high); }

TEST(LawSeeds, DevelopmentAndAcceptanceListsAreDisjointAndOfTheDocumentedSizes) {
  const auto development = development_law_seeds();
  const auto acceptance = acceptance_law_seeds();
  EXPECT_EQ(development.size(), 40u);
  EXPECT_EQ(acceptance.size(), 60u);
  const std::set<std::uint64_t> dev(development.begin(), development.end());
  const std::set<std::uint64_t> acc(acceptance.begin(), acceptance.end());
  EXPECT_EQ(dev.size(), development.size()) << "a development seed repeats";
  EXPECT_EQ(acc.size(), acceptance.size()) << "an acceptance seed repeats";
  for (std::uint64_t seed : acc) EXPECT_EQ(dev.count(seed), 0u) << seed;
  EXPECT_EQ(*dev.begin(), 1u);
  EXPECT_EQ(*dev.rbegin(), 40u);
  EXPECT_EQ(*acc.begin(), 9001u);
  EXPECT_EQ(*acc.rbegin(), 9060u);
}

// A short programme for the reproducibility checks: 2 h of a partial run.
Setpoint short_programme(const UnitLaw& unit) {
  Setpoint setpoint = draw_profile(ProfileKind::partial, unit, 11, 1);
  EXPECT_GT(setpoint.duration_s(), 3600.0);
  return setpoint;
}

TEST(LawFamily, TheSameSeedsGiveBitIdenticalRuns) {
  const UnitLaw first = draw_unit(7), second = draw_unit(7);
  EXPECT_EQ(first.describe(), second.describe());
  const Setpoint p1 = short_programme(first), p2 = short_programme(second);
  EXPECT_EQ(p1.time_s, p2.time_s);
  EXPECT_EQ(p1.temperature_c, p2.temperature_c);
  const ChamberRun a = simulate_unit(first, p1, 3), b = simulate_unit(second, p2, 3);
  ASSERT_EQ(a.column_names, b.column_names);
  for (std::size_t c = 0; c < a.columns.size(); ++c) EXPECT_EQ(a.columns[c], b.columns[c]) << a.column_names[c];
}

TEST(LawFamily, ADifferentNoiseSeedChangesTheGyroButNotTheDrift) {
  const UnitLaw unit = draw_unit(7);
  const Setpoint setpoint = short_programme(unit);
  const ChamberRun a = simulate_unit(unit, setpoint, 3), b = simulate_unit(unit, setpoint, 4);
  for (const std::string axis : {"x", "y", "z"}) {
    EXPECT_EQ(a.column("drift_" + axis), b.column("drift_" + axis)) << axis;
    EXPECT_NE(a.column("gyro_" + axis), b.column("gyro_" + axis)) << axis;
  }
  EXPECT_EQ(a.column("temp_chamber"), b.column("temp_chamber"));
}

TEST(LawFamily, DifferentLawSeedsDrawDifferentUnits) {
  EXPECT_NE(draw_unit(1).describe(), draw_unit(2).describe());
}

// Every documented range of docs/simulator.md, "The law family", for every development seed;
// and every alternative of every choice occurs at least once among them.
TEST(LawFamily, DevelopmentUnitsHaveTheirParametersInTheDocumentedRanges) {
  std::set<std::size_t> chain_lengths;
  std::set<int> sensor_sites;  // 0 case, 1 own chain, 2 another axis' chain
  std::set<int> shapes, hysteresis_kinds;
  int flicker = 0, quantized = 0;
  for (std::uint64_t seed : development_law_seeds()) {
    SCOPED_TRACE("law " + std::to_string(seed));
    const UnitLaw unit = draw_unit(seed);
    EXPECT_EQ(unit.seed, seed);
    EXPECT_TRUE(in_range(unit.min_c, -45, -25)) << unit.min_c;
    EXPECT_TRUE(in_range(unit.max_c, 50, 70)) << unit.max_c;
    EXPECT_TRUE(in_range(unit.reference_c, 15, 25)) << unit.reference_c;
    EXPECT_TRUE(in_range(unit.case_time_constant_s, 50, 800)) << unit.case_time_constant_s;
    EXPECT_TRUE(zero_or_in_range(unit.case_self_heating_c, 0.5, 5.0)) << unit.case_self_heating_c;
    for (std::size_t a = 0; a < 3; ++a) {
      SCOPED_TRACE("axis " + std::to_string(a));
      const AxisLaw& law = unit.axes[a];
      ASSERT_TRUE(in_range(static_cast<double>(law.node_time_constants_s.size()), 1, 3));
      chain_lengths.insert(law.node_time_constants_s.size());
      for (double tau : law.node_time_constants_s) EXPECT_TRUE(in_range(tau, 50, 2500)) << tau;
      EXPECT_TRUE(zero_or_in_range(law.back_coupling, 0.05, 0.5)) << law.back_coupling;
      EXPECT_TRUE(zero_or_in_range(law.self_heating_c, 0.5, 3.0)) << law.self_heating_c;
      ASSERT_TRUE(law.sensor_axis >= 0 && law.sensor_axis < 3);
      const auto& sensed_chain = unit.axes[static_cast<std::size_t>(law.sensor_axis)].node_time_constants_s;
      EXPECT_GE(law.sensor_node, -1);
      EXPECT_LT(law.sensor_node, static_cast<int>(sensed_chain.size()));
      sensor_sites.insert(law.sensor_node < 0 ? 0 : (law.sensor_axis == static_cast<int>(a) ? 1 : 2));
      EXPECT_TRUE(in_range(law.sensor_time_constant_s, 2, 60)) << law.sensor_time_constant_s;
      EXPECT_TRUE(in_range(law.bias_dph, -1, 1)) << law.bias_dph;
      shapes.insert(static_cast<int>(law.shape));
      if (law.shape == StaticShape::polynomial) {
        EXPECT_TRUE(magnitude_in_range(law.polynomial[0], 0.005, 0.05)) << law.polynomial[0];
        EXPECT_LE(std::abs(law.polynomial[1]), 8e-4);
        EXPECT_LE(std::abs(law.polynomial[2]), 1.5e-5);
        EXPECT_EQ(law.step_dph, 0.0);
      } else {
        EXPECT_LE(std::abs(law.polynomial[0]), 0.03);
        EXPECT_EQ(law.polynomial[1], 0.0);
        EXPECT_EQ(law.polynomial[2], 0.0);
        EXPECT_TRUE(magnitude_in_range(law.step_dph, 0.3, 1.5)) << law.step_dph;
        EXPECT_TRUE(in_range(law.step_centre_c, unit.min_c + 20, unit.max_c - 20)) << law.step_centre_c;
        EXPECT_TRUE(in_range(law.step_width_c, 8, 30)) << law.step_width_c;
      }
      EXPECT_TRUE(magnitude_in_range(law.rate_dph, 0.2, 2.5)) << law.rate_dph;
      EXPECT_TRUE(law.axial_gradient_dph == 0 || magnitude_in_range(law.axial_gradient_dph, 0.02, 0.2));
      EXPECT_TRUE(law.axial_gradient_rate_dph == 0 || magnitude_in_range(law.axial_gradient_rate_dph, 0.5, 3.0));
      if (law.radial_gradient_rate_dph != 0) {
        EXPECT_TRUE(magnitude_in_range(law.radial_gradient_rate_dph, 0.5, 4.0)) << law.radial_gradient_rate_dph;
        EXPECT_TRUE(in_range(law.radial_gain_s, 20, 150)) << law.radial_gain_s;
        EXPECT_TRUE(in_range(law.radial_time_constant_s, 60, 600)) << law.radial_time_constant_s;
      }
      hysteresis_kinds.insert(static_cast<int>(law.hysteresis));
      if (law.hysteresis == HysteresisKind::none) {
        EXPECT_EQ(law.hysteresis_dph, 0.0);
      } else {
        EXPECT_TRUE(magnitude_in_range(law.hysteresis_dph, 0.05, 0.5)) << law.hysteresis_dph;
      }
      if (law.hysteresis == HysteresisKind::memory) {
        EXPECT_TRUE(in_range(law.hysteresis_time_constant_s, 200, 3000)) << law.hysteresis_time_constant_s;
        EXPECT_TRUE(in_range(law.hysteresis_rate_scale, 0.05, 0.5)) << law.hysteresis_rate_scale;
      }
      if (law.hysteresis == HysteresisKind::play) {
        EXPECT_TRUE(in_range(law.hysteresis_width_c, 0.5, 5.0)) << law.hysteresis_width_c;
      }
      if (law.turn_on_dph != 0) {
        EXPECT_TRUE(magnitude_in_range(law.turn_on_dph, 0.05, 0.5)) << law.turn_on_dph;
        EXPECT_TRUE(in_range(law.turn_on_time_constant_s, 150, 900)) << law.turn_on_time_constant_s;
      }
    }
    const LawNoise& noise = unit.noise;
    EXPECT_TRUE(in_range(noise.angle_random_walk, 0.0015, 0.008)) << noise.angle_random_walk;
    EXPECT_TRUE(in_range(noise.bias_instability, 0.004, 0.02)) << noise.bias_instability;
    EXPECT_TRUE(in_range(noise.bias_correlation_time_s, 100, 3000)) << noise.bias_correlation_time_s;
    EXPECT_TRUE(zero_or_in_range(noise.quantization_arcsec, 0.01, 0.1)) << noise.quantization_arcsec;
    EXPECT_TRUE(in_range(noise.temperature_noise_c, 0.001, 0.02)) << noise.temperature_noise_c;
    const std::set<double> resolutions = {0.0001, 0.001, 0.01, 0.0625};
    EXPECT_EQ(resolutions.count(noise.temperature_resolution_c), 1u) << noise.temperature_resolution_c;
    flicker += noise.flicker ? 1 : 0;
    quantized += noise.quantization_arcsec > 0 ? 1 : 0;
  }
  EXPECT_EQ(chain_lengths, (std::set<std::size_t>{1, 2, 3}));
  EXPECT_EQ(sensor_sites, (std::set<int>{0, 1, 2}));
  EXPECT_EQ(shapes.size(), 2u);
  EXPECT_EQ(hysteresis_kinds.size(), 3u);
  EXPECT_GT(flicker, 0);
  EXPECT_LT(flicker, 40);
  EXPECT_GT(quantized, 0);
  EXPECT_LT(quantized, 40);
}

// The documented ramp rates of each kind, °C/min.
struct RateRange {
  double low, high;
};
RateRange documented_rates(ProfileKind kind) {
  switch (kind) {
    case ProfileKind::cycle: return {0.5, 1.5};
    case ProfileKind::slow: return {0.2, 0.7};
    case ProfileKind::fast: return {2, 3};
    case ProfileKind::staircase: return {2, 3};
    case ProfileKind::partial: return {0.5, 1.5};
    case ProfileKind::wander: return {0, 0};  // flat knots; the sines are checked apart
  }
  return {0, 0};
}

TEST(LawProfiles, EveryKindStaysInTheRatedRangeAtItsDocumentedRates) {
  for (std::uint64_t seed : development_law_seeds()) {
    const UnitLaw unit = draw_unit(seed);
    for (ProfileKind kind : kAllKinds) {
      for (int cycles = 1; cycles <= 3; ++cycles) {
        SCOPED_TRACE("law " + std::to_string(seed) + " " + to_string(kind) + " x" + std::to_string(cycles));
        const Setpoint setpoint = draw_profile(kind, unit, seed + 100, cycles);
        EXPECT_EQ(setpoint.name, to_string(kind));
        ASSERT_GE(setpoint.time_s.size(), 2u);
        ASSERT_EQ(setpoint.time_s.size(), setpoint.temperature_c.size());
        EXPECT_EQ(setpoint.time_s.front(), 0.0);
        EXPECT_EQ(setpoint.temperature(0), setpoint.temperature_c.front());
        EXPECT_EQ(setpoint.cycle_start_s.size(), kind == ProfileKind::wander ? 1u : static_cast<std::size_t>(cycles));
        EXPECT_EQ(setpoint.cycle_start_s.front(), 0.0);
        double fastest = 0, slowest = 1e9;
        for (std::size_t k = 1; k < setpoint.time_s.size(); ++k) {
          const double dt = setpoint.time_s[k] - setpoint.time_s[k - 1];
          ASSERT_GT(dt, 0.0) << "knot " << k;
          const double slope = std::abs(setpoint.temperature_c[k] - setpoint.temperature_c[k - 1]) / dt * 60.0;
          if (slope == 0) continue;
          fastest = std::max(fastest, slope);
          slowest = std::min(slowest, slope);
        }
        const RateRange rates = documented_rates(kind);
        if (kind == ProfileKind::wander) {
          EXPECT_EQ(fastest, 0.0);
        } else {
          EXPECT_LE(fastest, rates.high * (1 + 1e-12));
          EXPECT_GE(slowest, rates.low * (1 - 1e-12));
        }
        double low = 1e9, high = -1e9, steepest = 0, previous = setpoint.temperature(0);
        for (double t = 10; t <= setpoint.duration_s(); t += 10) {
          const double value = setpoint.temperature(t);
          low = std::min(low, value);
          high = std::max(high, value);
          steepest = std::max(steepest, std::abs(value - previous) / 10 * 60);
          previous = value;
        }
        EXPECT_GE(low, unit.min_c);
        EXPECT_LE(high, unit.max_c);
        if (kind == ProfileKind::wander) {
          // Sines within 0.45 of the range around its middle, no faster than documented.
          const double middle = 0.5 * (unit.min_c + unit.max_c), span = unit.max_c - unit.min_c;
          EXPECT_LE(std::max(high - middle, middle - low), 0.45 * span);
          EXPECT_GT(high - low, 0.1 * span);
          EXPECT_LE(steepest, 4.0);
          EXPECT_TRUE(in_range(setpoint.duration_s(), 6 * 3600.0 * cycles, 8 * 3600.0 * cycles));
        }
      }
    }
  }
}

TEST(LawProfiles, UnknownKindsAndCyclesAreUsageErrors) {
  EXPECT_EQ(parse_profile_kind("staircase"), ProfileKind::staircase);
  for (ProfileKind kind : kAllKinds) EXPECT_EQ(parse_profile_kind(to_string(kind)), kind);
  EXPECT_THROW(parse_profile_kind("nonsense"), UsageError);
  EXPECT_THROW(draw_profile(ProfileKind::cycle, draw_unit(1), 1, 0), UsageError);
}

// ---------------------------------------------------------------- closed forms

// One node per axis, no self-heating or back-coupling, the sensor on the coil with a lag far
// below the sample interval, a linear static law and no noise at all.
UnitLaw hand_built_unit() {
  UnitLaw unit;
  unit.case_time_constant_s = 300;
  unit.reference_c = 20;
  for (std::size_t a = 0; a < 3; ++a) {
    AxisLaw& law = unit.axes[a];
    law.node_time_constants_s = {400.0 + 100.0 * static_cast<double>(a)};
    law.sensor_axis = static_cast<int>(a);
    law.sensor_node = 0;
    law.sensor_time_constant_s = 0.2;
    law.bias_dph = 0.1 * static_cast<double>(a + 1);
    law.polynomial = {0.03 - 0.02 * static_cast<double>(a), 0, 0};
    law.rate_dph = 1.5 - static_cast<double>(a);
    law.radial_gradient_rate_dph = 0;
  }
  unit.noise = {.angle_random_walk = 0, .bias_instability = 0, .flicker = false, .bias_correlation_time_s = 600,
                .quantization_arcsec = 0, .temperature_noise_c = 0, .temperature_resolution_c = 0};
  return unit;
}

// From -30 °C at 0.5 °C/min for 3 h to 60 °C, then 6 h soak.
constexpr double kRampRate = 0.5 / 60.0;  // °C/s
Setpoint ramp_then_soak() {
  Setpoint setpoint;
  setpoint.time_s = {0, 10800, 32400};
  setpoint.temperature_c = {-30, 60, 60};
  setpoint.cycle_start_s = {0};
  return setpoint;
}

TEST(LawPhysics, UnderASteadyRampTheCoilLagsByRateTimesTheChainsTimeConstants) {
  const UnitLaw unit = hand_built_unit();
  const ChamberRun run = simulate_unit(unit, ramp_then_soak(), 1);
  const std::size_t row = 10000;  // 11 time constants into the ramp
  const double air = run.column("temp_chamber")[row];
  ASSERT_NEAR(air, -30 + kRampRate * 10000, 1e-9);
  for (std::size_t a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    const AxisLaw& law = unit.axes[a];
    const double chain_s = unit.case_time_constant_s + law.node_time_constants_s[0];
    const double coil = air - kRampRate * chain_s;
    EXPECT_NEAR(run.column("temp_" + axis)[row], coil - kRampRate * law.sensor_time_constant_s, 1e-3) << axis;
    const double drift = law.bias_dph + law.polynomial[0] * (coil - unit.reference_c) + law.rate_dph * kRampRate * 60;
    EXPECT_NEAR(run.column("drift_" + axis)[row], drift, 1e-4) << axis;
    EXPECT_EQ(run.column("gyro_" + axis)[row], run.column("drift_" + axis)[row]) << "no noise: gyro is the drift";
  }
}

TEST(LawPhysics, ALongSoakBringsTheSensorToTheAir) {
  const UnitLaw unit = hand_built_unit();
  const ChamberRun run = simulate_unit(unit, ramp_then_soak(), 1);
  const std::size_t last = run.rows() - 1;
  ASSERT_EQ(run.column("time_s")[last], 32400.0);
  for (std::size_t a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    const AxisLaw& law = unit.axes[a];
    EXPECT_NEAR(run.column("temp_" + axis)[last], 60.0, 1e-6) << axis;
    EXPECT_NEAR(run.column("drift_" + axis)[last], law.bias_dph + law.polynomial[0] * 40.0, 1e-6) << axis;
  }
}

// Self-heating of the case and of the chains, 3-node chains with back-coupling, and sensors
// on the case and on another axis' coil: after a soak each site sits at its steady rise.
TEST(LawPhysics, ASoakSettlesAtTheSelfHeatingRiseOfTheSensedSite) {
  UnitLaw unit = hand_built_unit();
  unit.case_self_heating_c = 2.0;
  unit.axes[0].self_heating_c = 1.0;   // x: sensor on its own coil -> air + 3
  unit.axes[1].self_heating_c = 0.5;   // y: sensor on the case -> air + 2
  unit.axes[1].sensor_node = -1;
  unit.axes[2].node_time_constants_s = {200, 300, 400};
  unit.axes[2].back_coupling = 0.3;
  unit.axes[2].self_heating_c = 0.0;   // z: sensor on x's coil -> air + 3
  unit.axes[2].sensor_axis = 0;
  unit.axes[2].sensor_node = 0;
  Setpoint soak;
  soak.time_s = {0, 30000};
  soak.temperature_c = {25, 25};
  soak.cycle_start_s = {0};
  const ChamberRun run = simulate_unit(unit, soak, 1);
  const std::size_t last = run.rows() - 1;
  EXPECT_NEAR(run.column("temp_x")[last], 28.0, 1e-6);
  EXPECT_NEAR(run.column("temp_y")[last], 27.0, 1e-6);
  EXPECT_NEAR(run.column("temp_z")[last], 28.0, 1e-6);
  // z's coil, behind its own three nodes, also settles at the case + its (zero) rise.
  EXPECT_NEAR(run.column("drift_z")[last], unit.axes[2].bias_dph + unit.axes[2].polynomial[0] * (27.0 - 20.0), 1e-6);
  // The unit starts at the air and warms: the sensors rise monotonically at the start.
  EXPECT_LT(run.column("temp_x")[100], run.column("temp_x")[1000]);
}

TEST(LawPhysics, TheTurnOnTransientDecaysWithItsTimeConstant) {
  UnitLaw unit = hand_built_unit();
  unit.axes[0].turn_on_dph = 0.4;
  unit.axes[0].turn_on_time_constant_s = 600;
  Setpoint flat;  // in equilibrium at 20 °C from power-on: every state stays put
  flat.time_s = {0, 3000};
  flat.temperature_c = {20, 20};
  const ChamberRun run = simulate_unit(unit, flat, 1);
  for (std::size_t row : {0u, 600u, 1800u}) {
    const double t = static_cast<double>(row);
    EXPECT_NEAR(run.column("drift_x")[row], unit.axes[0].bias_dph + 0.4 * std::exp(-t / 600), 1e-12) << row;
    EXPECT_NEAR(run.column("drift_y")[row], unit.axes[1].bias_dph, 1e-12) << row;
  }
}

// x's drift is its bias plus 0.3 °/h of the given hysteresis, nothing else.
UnitLaw hysteresis_only_unit(HysteresisKind kind) {
  UnitLaw unit = hand_built_unit();
  AxisLaw& law = unit.axes[0];
  law.polynomial = {0, 0, 0};
  law.rate_dph = 0;
  law.hysteresis = kind;
  law.hysteresis_dph = 0.3;
  return unit;
}

// Play hysteresis: after heating the coil sits w above the play state, after cooling w below,
// and a soak keeps the sign (the unit remembers the direction of the last movement).
TEST(LawPhysics, ThePlayOperatorRemembersTheDirectionOfTheLastMovement) {
  UnitLaw unit = hysteresis_only_unit(HysteresisKind::play);
  AxisLaw& law = unit.axes[0];
  law.hysteresis_width_c = 2.0;
  Setpoint programme;  // up 20 °C, soak 3 h, down 20 °C, soak 3 h, up 1 °C (inside the play), soak
  programme.time_s = {0, 2400, 13200, 15600, 26400, 26520, 37320};
  programme.temperature_c = {20, 40, 40, 20, 20, 21, 21};
  const ChamberRun run = simulate_unit(unit, programme, 1);
  const auto& drift = run.column("drift_x");
  EXPECT_NEAR(drift[13200], law.bias_dph + 0.3, 1e-9);
  EXPECT_NEAR(drift[26400], law.bias_dph - 0.3, 1e-9);
  // 1 °C up from the bottom of the play: (Tc - p)/w goes from -1 to -1 + 1/2.
  EXPECT_NEAR(drift[37320], law.bias_dph - 0.15, 1e-6);
}

TEST(LawPhysics, TheMemoryStateFollowsTheRateAndFadesInASoak) {
  UnitLaw unit = hysteresis_only_unit(HysteresisKind::memory);
  AxisLaw& law = unit.axes[0];
  law.hysteresis_time_constant_s = 300;
  law.hysteresis_rate_scale = 0.2;
  const ChamberRun run = simulate_unit(unit, ramp_then_soak(), 1);
  const auto& drift = run.column("drift_x");
  // Steady ramp at 0.5 °C/min: h -> tanh(0.5 / 0.2).
  EXPECT_NEAR(drift[10000], law.bias_dph + 0.3 * std::tanh(0.5 / 0.2), 1e-4);
  EXPECT_NEAR(drift[32400], law.bias_dph, 1e-6);
}

// The law's regressors are the states simulate_unit evaluates the drift on: their product
// with the law's coefficients is the drift column to the last rounding, on drawn units
// with every kind of term, and a term the law lacks is a column of zeros.
TEST(LawRegressors, TheirProductWithTheCoefficientsIsTheSimulatedDrift) {
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const UnitLaw unit = draw_unit(seed);
    const Setpoint programme = draw_profile(ProfileKind::staircase, unit, seed);
    const ChamberRun run = simulate_unit(unit, programme, 7);
    const LawRegressors regressors = law_regressors(unit, programme);
    for (std::size_t a = 0; a < 3; ++a) {
      const auto& drift = run.column(std::string("drift_") + "xyz"[a]);
      ASSERT_EQ(regressors[a].size(), kLawRegressors);
      ASSERT_EQ(regressors[a][0].size(), drift.size());
      const auto c = law_coefficients(unit.axes[a]);
      double worst = 0;
      for (std::size_t row = 0; row < drift.size(); row += 7) {
        double sum = 0;
        for (std::size_t j = 0; j < kLawRegressors; ++j) sum += c[j] * regressors[a][j][row];
        worst = std::max(worst, std::abs(sum - drift[row]));
      }
      EXPECT_LT(worst, 1e-12) << "law " << seed << " axis " << a;
      const auto zeros = [&](std::size_t j) {
        return std::all_of(regressors[a][j].begin(), regressors[a][j].end(), [](double v) { return v == 0; });
      };
      const auto& law = unit.axes[a];
      EXPECT_EQ(zeros(4), law.shape != StaticShape::tanh_step) << "the tanh step";
      EXPECT_EQ(zeros(9), law.hysteresis != HysteresisKind::memory) << "the memory";
    }
  }
}

// On the hand-built unit's ramp the regressors take their closed forms: ΔTc, the coil's rate
// in °C/min, no gradient upstream beyond the coil's lag, the turn-on decay from power-on.
TEST(LawRegressors, OnASteadyRampTheyTakeTheirClosedForms) {
  const UnitLaw unit = hand_built_unit();
  const LawRegressors regressors = law_regressors(unit, ramp_then_soak());
  const auto names = law_regressor_names();
  ASSERT_EQ(names[1], "dTc");
  ASSERT_EQ(names[5], "coil_rate");
  const std::size_t row = 10000;
  const double air = -30 + kRampRate * 10000;
  for (std::size_t a = 0; a < 3; ++a) {
    const double tau = unit.axes[a].node_time_constants_s[0];
    const double coil = air - kRampRate * (unit.case_time_constant_s + tau);
    EXPECT_NEAR(regressors[a][0][row], 1.0, 0) << a;
    EXPECT_NEAR(regressors[a][1][row], coil - unit.reference_c, 1e-3) << a;
    EXPECT_NEAR(regressors[a][2][row], (coil - unit.reference_c) * (coil - unit.reference_c), 0.1) << a;
    EXPECT_NEAR(regressors[a][5][row], kRampRate * 60, 1e-5) << a;
    EXPECT_NEAR(regressors[a][6][row], kRampRate * tau, 1e-3) << "the case leads the coil by rate times τ";
    EXPECT_NEAR(regressors[a][11][row], std::exp(-10000.0 / unit.axes[a].turn_on_time_constant_s), 1e-15) << a;
  }
}

// The chain's time constants shorter than the sample interval stay stable: RK4 substeps.
TEST(LawPhysics, ASampleIntervalLongerThanTheSensorLagStaysStable) {
  const UnitLaw unit = hand_built_unit();  // sensor lag 0.2 s
  const ChamberRun slow = simulate_unit(unit, ramp_then_soak(), 1, 0.1);  // 10-s samples
  const ChamberRun fast = simulate_unit(unit, ramp_then_soak(), 1, 1.0);
  ASSERT_EQ(slow.rows(), 3241u);
  for (std::size_t row = 0; row < slow.rows(); row += 100) {
    EXPECT_NEAR(slow.column("temp_x")[row], fast.column("temp_x")[10 * row], 1e-4) << row;
    EXPECT_NEAR(slow.column("drift_x")[row], fast.column("drift_x")[10 * row], 1e-4) << row;
  }
}

// ---------------------------------------------------------------- the states rebuilt

// RMS difference of one regressor, rebuilt and true, from `first` on.
double rms_error(const LawRegressors& rebuilt, const LawRegressors& truth, std::size_t axis, std::size_t regressor,
                 std::size_t first) {
  double sum = 0;
  const auto& a = rebuilt[axis][regressor];
  const auto& b = truth[axis][regressor];
  for (std::size_t row = first; row < a.size(); ++row) sum += (a[row] - b[row]) * (a[row] - b[row]);
  return std::sqrt(sum / static_cast<double>(a.size() - first));
}

// With thermometers a hundred times better than drawn, the filter on the law's own network
// gives its states back, on drawn units with every kind of chain and sensor: the coil's
// temperature and its rate within 1e-4 (°C, °C/min; measured: 5e-7 to 4.5e-6).
TEST(RebuiltRegressors, FromNearlyExactThermometersTheyAreTheTrueStates) {
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    UnitLaw unit = draw_unit(seed);
    unit.noise.temperature_noise_c = 5e-5;
    unit.noise.temperature_resolution_c = 0;
    const Setpoint programme = draw_profile(ProfileKind::cycle, unit, seed);
    const ChamberRun run = simulate_unit(unit, programme, 7);
    const LawRegressors truth = law_regressors(unit, programme);
    const RebuiltRegressors rebuilt = law_regressors_from_thermometers(unit, run, 1e-8, 100);
    for (std::size_t a = 0; a < 3; ++a) {
      SCOPED_TRACE("law " + std::to_string(seed) + " axis " + std::to_string(a));
      EXPECT_LT(rms_error(rebuilt.regressors, truth, a, 1, 1800), 1e-4) << "dTc";
      EXPECT_LT(rms_error(rebuilt.regressors, truth, a, 5, 1800), 1e-4) << "coil_rate";
      EXPECT_EQ(rebuilt.regressors[a][11], truth[a][11]) << "the turn-on transient is a function of time";
    }
  }
}

// A coil upstream of its thermometer is seen late: the filter, reading only rows up to
// now, is behind it on every ramp; reading 100 s ahead removes most of that error, and the
// whole run (the smoother) no less (measured: the coil's rate 0.0016 °C/min RMS now, 0.0004
// 100 s ahead, 0.0003 from the whole run).
TEST(RebuiltRegressors, ACoilUpstreamOfItsThermometerIsSeenBetterAhead) {
  UnitLaw unit = hand_built_unit();
  unit.axes[1].node_time_constants_s = {1500};
  unit.axes[0].sensor_axis = 1;  // x's thermometer on y's coil, 1,100 s behind x's
  unit.noise.temperature_noise_c = 0.005;
  unit.noise.temperature_resolution_c = 0.001;
  const Setpoint programme = ramp_then_soak();
  const ChamberRun run = simulate_unit(unit, programme, 3);
  const LawRegressors truth = law_regressors(unit, programme);
  const auto coil_rate_error = [&](double lookahead_s) {
    return rms_error(law_regressors_from_thermometers(unit, run, 1e-8, lookahead_s).regressors, truth, 0, 5, 1800);
  };
  const double now = coil_rate_error(0);
  const double ahead = coil_rate_error(100);
  const double whole = coil_rate_error(std::numeric_limits<double>::infinity());
  EXPECT_LT(ahead, 0.5 * now) << now << " °C/min now, " << ahead << " ahead";
  EXPECT_LT(whole, 1.05 * ahead) << whole << " °C/min from the whole run";
}

// The likelihood the intensity is chosen by prefers an air rate that can follow the
// programme's corners to one that cannot.
TEST(RebuiltRegressors, TheLikelihoodRejectsAnAirThatCannotTurn) {
  const UnitLaw unit = draw_unit(4);
  const ChamberRun run = simulate_unit(unit, draw_profile(ProfileKind::cycle, unit, 4), 2);
  const double stiff = law_regressors_from_thermometers(unit, run, 1e-14).log_likelihood;
  const double free = law_regressors_from_thermometers(unit, run, 1e-8).log_likelihood;
  EXPECT_GT(free, stiff);
}

// ---------------------------------------------------------------- noise

// At 100-s smoothing the white part ARW²·3600/w of the floor is always there; the bias adds
// at most its stationary variance and the quantization 2(q²/12)/w². A slip in the white
// noise's scaling with the sample interval shows at 2 Hz.
TEST(LawNoise, TheNoiseFloorIsAboveItsWhitePartAndBelowItsBound) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const UnitLaw unit = draw_unit(seed);
    const Setpoint setpoint = draw_profile(ProfileKind::cycle, unit, seed, 1);
    for (double rate_hz : {1.0, 2.0}) {
      SCOPED_TRACE("law " + std::to_string(seed) + " at " + std::to_string(rate_hz) + " Hz");
      const ChamberRun run = simulate_unit(unit, setpoint, 5, rate_hz);
      const double window = 100;
      const double white = unit.noise.angle_random_walk * unit.noise.angle_random_walk * 3600 / window;
      // Stationary variance of the bias: one process, or at most four of the same size (flicker).
      const double sigma = unit.noise.bias_instability * 0.6643 / 0.6174;
      const double bias = (unit.noise.flicker ? 4.0 : 1.0) * sigma * sigma;
      const double quantum = unit.noise.quantization_arcsec;
      const double bound = white + bias + 2 * quantum * quantum / 12 / (window * window);
      const auto floor = run.noise_floor(window);
      for (double axis_floor : floor) {
        EXPECT_GT(axis_floor, 0.85 * white);
        EXPECT_LT(axis_floor, 1.25 * bound);
      }
    }
  }
}

}  // namespace
}  // namespace thermodrift::sim
