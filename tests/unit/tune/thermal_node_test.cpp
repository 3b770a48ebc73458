// The thermal-node identification (`--features auto`) against units whose physics is known:
// one axis per structure it must recover. Trained on the first cycle of a chamber
// programme, the identified terms are checked for the structure (the node's delay behind
// the sensor, a memory, a play) and the linear model on them for its held-out error on the
// next cycle against the simulator's noise floor.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <utility>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "thermodrift/models/linear.hpp"
#include "thermodrift/sim/law_family.hpp"
#include "thermodrift/sim/standard_normal.hpp"
#include "thermodrift/tune/calibration.hpp"
#include "tune/term_columns.hpp"

namespace thermodrift {
namespace {

// The case 300 s behind the air; every sensor on the case (10 s of its own), the coils behind
// it: x one node of 600 s with a direction memory, y two nodes of 300 s and 900 s in series,
// z one node of 500 s with a play of ±2 °C. Navigation-grade noise.
sim::UnitLaw known_unit() {
  sim::UnitLaw unit;
  unit.case_time_constant_s = 300;
  unit.reference_c = 20;
  unit.min_c = -40, unit.max_c = 60;
  const std::vector<std::vector<double>> chains = {{600}, {300, 900}, {500}};
  for (std::size_t a = 0; a < 3; ++a) {
    sim::AxisLaw& law = unit.axes[a];
    law.node_time_constants_s = chains[a];
    law.sensor_axis = static_cast<int>(a);
    law.sensor_node = -1;
    law.sensor_time_constant_s = 10;
  }
  unit.axes[0].polynomial = {0.03, 4e-4, 0};
  unit.axes[0].rate_dph = 1.0;
  unit.axes[0].hysteresis = sim::HysteresisKind::memory;
  unit.axes[0].hysteresis_dph = 0.3;
  unit.axes[0].hysteresis_time_constant_s = 900;
  unit.axes[1].polynomial = {-0.04, 6e-4, 0};
  unit.axes[1].rate_dph = -0.8;
  unit.axes[2].polynomial = {0.02, -5e-4, 0};  // curved: a linear map would leave the node's delay free
  unit.axes[2].rate_dph = 1.2;
  unit.axes[2].hysteresis = sim::HysteresisKind::play;
  unit.axes[2].hysteresis_dph = 0.4;
  unit.axes[2].hysteresis_width_c = 2;
  unit.noise.angle_random_walk = 0.003;
  unit.noise.bias_instability = 0.003;
  unit.noise.temperature_noise_c = 0.002;
  unit.noise.temperature_resolution_c = 0.001;
  return unit;
}

// The decimals a term name writes its constants with, at most (knots 0.1 °C, play widths
// 0.01 °C, memory rate scales 0.01 °C/min, time constants whole seconds): a name such as
// play:29:2.3000000000000003 prints the rounding of a product, not the constant chosen.
std::size_t most_decimals(const std::string& name) {
  std::size_t most = 0, digits = 0;
  bool after_point = false;
  for (const char c : name) {
    if (c == '.') {
      after_point = true, digits = 0;
    } else if (c >= '0' && c <= '9') {
      if (after_point) most = std::max(most, ++digits);
    } else {
      after_point = false;
    }
  }
  return most;
}

// The delay of the identified node behind the sensor at low frequency, s: T1 + T2 - TL.
double node_delay(const Pipeline& pipeline) {
  double lags = 0, lead = 0;
  for (const auto& term : pipeline.terms) {
    const FeatureAtom& atom = term.factors.front().atom;
    if ((atom.kind == FeatureAtom::Kind::lag || atom.kind == FeatureAtom::Kind::lag2) && lags == 0) {
      lags = atom.tau + atom.tau2;
    }
    if (atom.kind == FeatureAtom::Kind::node_hinge) lead = atom.zero;
  }
  return lags - lead;
}

bool has_atom(const Pipeline& pipeline, FeatureAtom::Kind kind, double* level = nullptr) {
  for (const auto& term : pipeline.terms) {
    for (const auto& factor : term.factors) {
      if (factor.atom.kind != kind) continue;
      if (level) *level = factor.atom.level;
      return true;
    }
  }
  return false;
}

// Where the identification averaged several searches (fit.feature_selection's "average"
// step), the model is the mean of the kept members' least-squares fits, each on its own
// terms of the training log, and the blocked CV MSE of that mean is at most the mean of
// theirs (each member's pooled CV MSE recomputed here: the path scores them by the typical
// block). Returns whether the axis was averaged.
bool check_average(const AxisModel& axis, const ChamberLog& training, std::size_t a) {
  const SelectionRecord& selection = axis.fit.feature_selection.value();
  const auto& path = selection.path;
  std::vector<std::vector<std::string>> member_terms;
  std::string kept;
  for (const auto& step : path) {
    if (step.action == "member") member_terms.push_back(step.terms);
    if (step.action == "average") kept = step.term;
  }
  EXPECT_GE(member_terms.size(), 3u) << "one search per memory rate scale at least";
  if (kept.empty()) return false;
  const FeatureTable union_table = feature_table({training}, axis.pipeline, a, true);
  const Eigen::VectorXd averaged = axis.predict(union_table.features);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(averaged.size());
  double mean_cv = 0;
  int count = 0;
  for (std::size_t m = 0; m < member_terms.size(); ++m) {
    // "members 1, 3, 4 (2 distinct sets), ...": the numbers before the parenthesis
    const std::string numbers = ", " + kept.substr(8, kept.find(" (") - 8) + ",";
    if (numbers.find(fmt::format(" {},", m + 1)) == std::string::npos) continue;
    Pipeline pipeline = axis.pipeline;
    pipeline.terms.clear();
    for (const auto& name : member_terms[m]) pipeline.terms.push_back(FeatureTerm::parse(name));
    const FeatureTable table = feature_table({training}, pipeline, a, true);
    mean += fit_least_squares(table.features, table.target, linear_regressors(pipeline.terms.size())).predict(table.features);
    const auto blocks = cv_blocks(table.target.size(), {0}, static_cast<int>(selection.folds), FoldsBy::time).blocks;
    mean_cv += least_squares_cv(table.features, table.target, blocks);
    ++count;
  }
  EXPECT_GE(count, 2);
  mean /= count;
  EXPECT_LT((averaged - mean).cwiseAbs().maxCoeff(), 1e-6 * averaged.cwiseAbs().maxCoeff());
  EXPECT_LE(selection.cv_mse, mean_cv / count * (1 + 1e-9));
  return true;
}

// Axis a alone, with every thermometer, its own first.
ChamberLog axis_alone(ChamberLog log, std::size_t a) {
  log.gyro = {log.gyro[a]}, log.gyro_names = {log.gyro_names[a]};
  std::swap(log.temperature[0], log.temperature[a]);
  std::swap(log.temperature_names[0], log.temperature_names[a]);
  return log;
}

// Axis a of development law `seed` alone (every thermometer, its own first): cycle 1 of a
// two-cycle run as the training log, a new run of the unit through a programme of `kind`,
// and that run's noise floor from 1800 s on.
struct LawAxis {
  ChamberLog training, other;
  double floor = 0;
};

LawAxis law_axis(std::uint64_t seed, std::size_t a, sim::ProfileKind kind) {
  const sim::UnitLaw unit = sim::draw_unit(seed);
  const sim::ChamberRun run =
      sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, seed, 2), sim::derive_seed(seed, 1));
  const sim::ChamberRun other =
      sim::simulate_unit(unit, sim::draw_profile(kind, unit, sim::derive_seed(seed, 12), 1), sim::derive_seed(seed, 2));
  return {slice_rows(axis_alone(sim::to_chamber_log(run), a), 0, run.cycle_start_rows().at(1)),
          axis_alone(sim::to_chamber_log(other), a), other.noise_floor(100, 1800)[a]};
}

// `--model linear --features auto` fitted on cycle 1 of a run, judged on cycle 2 with the
// states carried over from cycle 1; the floor is the simulator's, of cycle 2's rows.
struct NextCycleFit {
  ChamberLog first_cycle;
  Calibration calibration;
  std::vector<ResidualMetrics> held_out;
  std::array<double, 3> floor{};
};

NextCycleFit fit_first_cycle(const sim::ChamberRun& run) {
  const std::size_t split = run.cycle_start_rows().at(1);
  const ChamberLog log = sim::to_chamber_log(run);
  NextCycleFit fit{slice_rows(log, 0, split), {}, {}, run.noise_floor(100, split)};
  CalibrationOptions options;
  options.model = ModelKind::linear;
  options.terms = {"auto"};
  EXPECT_EQ(options.selection.method, FeatureSelectionOptions::Method::thermal_node) << "the default search";
  fit.calibration = calibrate({fit.first_cycle}, LogSpec{}, options);
  fit.held_out = evaluate_from(fit.calibration.model, log, split);
  return fit;
}

TEST(ThermalNode, RecoversTheNodeItsMemoryAndItsPlayAndPredictsTheNextCycle) {
  const sim::UnitLaw unit = known_unit();
  const sim::ChamberRun run = sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 3, 2), 4);
  const auto [first_cycle, calibration, held_out, floor] = fit_first_cycle(run);

  const double true_delay[3] = {600, 1200, 500};
  int averaged = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    averaged += check_average(calibration.model.axes[a], first_cycle, a);
    const Pipeline& pipeline = calibration.model.axes[a].pipeline;
    std::string names;
    for (const auto& name : pipeline.term_names()) names += name + " ";
    SCOPED_TRACE(std::string(1, "xyz"[a]) + ": " + names);
    std::printf("%c: delay %.0f s (true %.0f), held-out %.2f x floor; %s\n", "xyz"[a], node_delay(pipeline),
                true_delay[a], held_out[a].mse_after / floor[a], names.c_str());
    EXPECT_NEAR(node_delay(pipeline), true_delay[a], 0.25 * true_delay[a]);
    EXPECT_LT(held_out[a].mse_after / floor[a], 3.0) << "held-out MSE over the noise floor, next cycle";
  }
  EXPECT_GE(averaged, 1) << "no axis averaged: the check above checked nothing";
  EXPECT_TRUE(has_atom(calibration.model.axes[0].pipeline, FeatureAtom::Kind::direction));
  double width = 0;
  ASSERT_TRUE(has_atom(calibration.model.axes[2].pipeline, FeatureAtom::Kind::play, &width));
  EXPECT_GT(width, 1.0);
  EXPECT_LT(width, 4.0);
  for (const auto& axis : calibration.model.axes) {
    for (const auto& name : axis.pipeline.term_names()) EXPECT_LE(most_decimals(name), 2u) << name;
  }
}

// Thermometers swapped between blocks: x's own sits on y's far node (a 1600 s node behind
// a 400 s one), y's own on x's coil (600 s behind the case). Each axis' coil is then
// measured by the other axis' thermometer, and its own lags or leads it by a thousand
// seconds. x's node is found on y's thermometer, its delay behind it short, and every
// axis' next cycle is held to the same bound as the plain units above.
TEST(ThermalNode, FindsTheNodeOnAnotherAxisThermometer) {
  sim::UnitLaw unit = known_unit();
  unit.axes[0].hysteresis = sim::HysteresisKind::none;
  unit.axes[1].node_time_constants_s = {400, 1600};
  unit.axes[0].sensor_axis = 1, unit.axes[0].sensor_node = 1;
  unit.axes[1].sensor_axis = 0, unit.axes[1].sensor_node = 0;
  const sim::ChamberRun run = sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 3, 2), 4);
  const std::size_t split = run.cycle_start_rows().at(1);
  const ChamberLog log = sim::to_chamber_log(run);
  const ChamberLog first_cycle = slice_rows(log, 0, split);

  CalibrationOptions options;
  options.model = ModelKind::linear;
  options.terms = {"auto"};
  options.selection.other_channels = true;
  const Calibration calibration = calibrate({first_cycle}, LogSpec{}, options);
  const auto held_out = evaluate_from(calibration.model, log, split);
  options.selection.other_channels = false;
  const auto own_channel = evaluate_from(calibrate({first_cycle}, LogSpec{}, options).model, log, split);
  const auto floor = run.noise_floor(100, split);
  for (std::size_t a = 0; a < 3; ++a) {
    const Pipeline& pipeline = calibration.model.axes[a].pipeline;
    std::printf("%c: channel %zu, delay %.0f s, held-out %.2f x floor (own channel only: %.2f); %s\n", "xyz"[a],
                pipeline.temperature_input(a) + 1, node_delay(pipeline), held_out[a].mse_after / floor[a],
                own_channel[a].mse_after / floor[a], fmt::format("{}", fmt::join(pipeline.term_names(), " ")).c_str());
    EXPECT_LT(held_out[a].mse_after / floor[a], 3.0) << "xyz"[a] << ": held-out MSE over the noise floor, next cycle";
  }
  // x's own thermometer is on y's far node, 2,000 s from the case, x's coil 600 s: on it,
  // 8.7x the floor. y's coil is described as well by a lag of y's own thermometer (on x's
  // coil, some 1,400 s upstream) as by x's, which sits on it (2.0x either way; scored by
  // the pooled CV MSE the search took x's): either may be kept. z has only its own.
  EXPECT_EQ(calibration.model.axes[0].pipeline.temperature_channel, std::optional<std::size_t>(1));
  EXPECT_LT(held_out[0].mse_after, 0.5 * own_channel[0].mse_after) << "x: the other thermometer must pay";
  EXPECT_EQ(calibration.model.axes[2].pipeline.temperature_channel, std::nullopt);
  EXPECT_LT(std::abs(node_delay(calibration.model.axes[0].pipeline)), 300.0) << "x's coil is y's thermometer's node";
}

// A gyro with a turn-on transient: x's drift has 0.4 °/h decaying over 400 s after power-on,
// beside its node, memory and static map (the unit above otherwise). Searched without the
// start-of-run terms (as for a log that starts with the unit running), the first minutes
// of the training cycle bend x's other coefficients; with them (the default), x takes an
// on:TAU term and the next cycle, judged with the states carried over as a running
// compensator carries them, is missed by much less. (On a new run of a slow programme the
// two fits differ by which memory each search keeps, not by the start: measured 10.6x the
// floor with the terms, 4.2x without, from 1800 s on and alike from 5400 s on.)
TEST(ThermalNode, FindsTheStartOfARun) {
  sim::UnitLaw unit = known_unit();
  unit.axes[0].turn_on_dph = 0.4;
  unit.axes[0].turn_on_time_constant_s = 400;
  const sim::ChamberRun run = sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 3, 2), 4);
  const std::size_t split = run.cycle_start_rows().at(1);
  const ChamberLog log = sim::to_chamber_log(run);
  const ChamberLog training = slice_rows(log, 0, split);
  const double floor = run.noise_floor(100, split)[0];
  double ratio[2] = {0, 0};
  for (const bool power_on : {true, false}) {
    CalibrationOptions options;
    options.model = ModelKind::linear;
    options.terms = {"auto"};
    options.selection.power_on_start = power_on;
    const Calibration calibration = calibrate({training}, LogSpec{}, options);
    ratio[power_on ? 0 : 1] = evaluate_from(calibration.model, log, split)[0].mse_after / floor;
    const Pipeline& pipeline = calibration.model.axes[0].pipeline;
    std::printf("%s: next cycle %.2f x floor; %s\n", power_on ? "power-on" : "running", ratio[power_on ? 0 : 1],
                fmt::format("{}", fmt::join(pipeline.term_names(), " ")).c_str());
    EXPECT_EQ(has_atom(pipeline, FeatureAtom::Kind::turn_on), power_on);
    for (std::size_t a = 1; a < 3 && !power_on; ++a) {
      EXPECT_FALSE(has_atom(calibration.model.axes[a].pipeline, FeatureAtom::Kind::turn_on)) << "xyz"[a];
    }
  }
  // Scored by the pooled CV MSE, the search without the terms let the first minutes bend
  // x's coefficients (next cycle 2x worse and more). Scored by the typical block, one
  // block's transient no longer decides, and the fits meet (2.2x either way): the terms
  // must be found and must not cost.
  EXPECT_LT(ratio[0], 1.25 * ratio[1]) << "held-out MSE over the noise floor, next cycle carried";
  EXPECT_LT(ratio[0], 3.0);
}

// A fit that is a small difference of large terms fails on any data whose states differ
// from the training log's. Development law 29, axis y: z's thermometer sits on y's coil,
// y's own on the case, so the measured gradient grad:2-3 is nearly the coil's lag behind
// the case, collinear with the node's rates over one cycle. Without a bound the search
// keeps sets whose parts cancel about 250-fold (the CV rewards them; their average about
// 100-fold), and the next cycle, its lags started in equilibrium after a ramp, is missed
// by 3·10⁵ times the floor; with the default bound the set cancels 3-fold and the next
// cycle is missed by 165 times the floor (as before measured gradients were offered).
// Searched without the start-of-run terms (as for a log that starts with the unit
// running): with them, this law's unbounded search ends on a set that cancels 18-fold
// (262x the floor, bounded 147x), and the bound has nothing to show here.
TEST(ThermalNode, BoundsHowMuchTheFitCancels) {
  const std::uint64_t seed = 29;
  const sim::UnitLaw unit = sim::draw_unit(seed);
  const sim::ChamberRun run =
      sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, seed, 2), sim::derive_seed(seed, 1));
  const std::size_t split = run.cycle_start_rows().at(1);
  const ChamberLog log = axis_alone(sim::to_chamber_log(run), 1);
  const ChamberLog training = slice_rows(log, 0, split);
  const ChamberLog next_cycle = slice_rows(log, split, log.rows());
  const auto floor = run.noise_floor(100, split + 1800)[1];

  double ratio[2] = {0, 0}, cancelled[2] = {0, 0};
  for (const bool bounded : {true, false}) {
    CalibrationOptions options;
    options.model = ModelKind::linear;
    options.terms = {"auto"};
    if (!bounded) options.selection.max_cancellation = std::numeric_limits<double>::infinity();
    // On y's own channel (--node-channel own): on z's, which sits on y's coil, the node is a plain
    // 8 s lag that cancels nothing (137x on the next cycle): nothing to bound.
    options.selection.other_channels = false;
    options.selection.power_on_start = false;
    const Calibration calibration = calibrate({training}, LogSpec{}, options);
    const AxisModel& axis = calibration.model.axes[0];
    const FeatureTable table = feature_table({training}, axis.pipeline, 0, true);
    Eigen::Index hinges = 0;
    for (const auto& name : axis.pipeline.term_names()) hinges += name.find("hinge:") != std::string::npos;
    cancelled[bounded ? 0 : 1] = cancellation(table.features, std::get<LinearModel>(axis.model).coefficients, 1 + hinges);
    ratio[bounded ? 0 : 1] = evaluate(calibration.model, {next_cycle}, 1800)[0].mse_after / floor;
    std::printf("%s: cancellation %.1f, next cycle %.3g x floor; %s\n", bounded ? "bounded" : "unbounded",
                cancelled[bounded ? 0 : 1], ratio[bounded ? 0 : 1],
                fmt::format("{}", fmt::join(axis.pipeline.term_names(), " ")).c_str());
  }
  EXPECT_GT(cancelled[1], 50.0) << "the unbounded search no longer keeps a cancelling set: the test tests nothing";
  EXPECT_LT(cancelled[0], CalibrationOptions{}.selection.max_cancellation);
  EXPECT_LT(100 * ratio[0], ratio[1]) << "held-out MSE over the noise floor, next cycle settled 1800 s";
}

// The node and its thermometer are chosen before any dynamic term, so an unmodelled memory
// can pick a node that absorbs it, and the terms grown on that node make up for it.
// Development law 9, axis y: the coil is two lags (3,059 s and 199 s, back-coupled) behind
// its thermometer, with a memory of 0.33 °/h. Chosen once, the node is a 1,032 s lag of
// another axis' thermometer; searched again under the grown terms (the default), the own
// channel's grown model wins, with a node found again on it. The model's CV MSE and its
// error on a slow programme (a new run of the unit) must both fall.
TEST(ThermalNode, SearchesTheNodeAndItsThermometerAgainUnderItsDynamicTerms) {
  const auto [training, other, floor] = law_axis(9, 1, sim::ProfileKind::slow);

  double cv[2] = {0, 0}, ratio[2] = {0, 0};
  bool renoded[2] = {false, false}, own_channel[2] = {false, false};
  std::string channel_step;
  for (const bool again : {true, false}) {
    CalibrationOptions options;
    options.model = ModelKind::linear;
    options.terms = {"auto"};
    options.selection.node_under_dynamics = again;
    // The pooled score this was measured under (28.5x against 542x here). Scored by the
    // typical block (the default) this slow programme is missed either way (the search
    // again 664x, once 518x), while the benchmark's tests of development law 9 y went from
    // 5.1-8.7x to 1.8-2.8x (docs/generalization.md, "Scored by the typical block").
    options.selection.cv_score = FeatureSelectionOptions::CvScore::pooled;
    const Calibration calibration = calibrate({training}, LogSpec{}, options);
    const AxisModel& axis = calibration.model.axes[0];
    const SelectionRecord& selection = axis.fit.feature_selection.value();
    cv[again ? 0 : 1] = selection.cv_mse;
    for (const auto& step : selection.path) {
      renoded[again ? 0 : 1] |= step.action == "renode";
      if (again && step.action == "channel") channel_step = step.term;
    }
    own_channel[again ? 0 : 1] = !axis.pipeline.temperature_channel.has_value();
    ratio[again ? 0 : 1] = evaluate(calibration.model, {other}, 1800)[0].mse_after / floor;
    std::printf("%s: CV MSE %.3g, slow programme %.3g x floor; %s\n", again ? "again" : "once", cv[again ? 0 : 1],
                ratio[again ? 0 : 1], fmt::format("{}", fmt::join(axis.pipeline.term_names(), " ")).c_str());
  }
  EXPECT_FALSE(own_channel[1]) << "chosen once, the node is no longer on another channel: the test tests less";
  EXPECT_TRUE(own_channel[0]);
  EXPECT_NE(channel_step.find("the own kept"), std::string::npos) << channel_step;
  EXPECT_TRUE(renoded[0]);
  EXPECT_FALSE(renoded[1]);
  EXPECT_LT(2 * cv[0], cv[1]) << "CV MSE of the search, (°/h)²";
  EXPECT_LT(2 * ratio[0], ratio[1]) << "held-out MSE over the noise floor, slow programme settled 1800 s";
}

// A rate response that is not linear in the coil's rate: heating and cooling at the same
// speed drift by different amounts (a·r·tanh(r/0.05), r the coil's rate in °C/min), and the
// rate sensitivity changes with temperature (b·ΔTc·r). Added to x of the known unit, without
// its memory, from the simulator's true coil states. The search offers both as products of
// the node's own terms; it must take them, and the next cycle must hold the plain bound.
TEST(ThermalNode, FindsAnAsymmetricAndATemperatureDependentRateResponse) {
  sim::UnitLaw unit = known_unit();
  unit.axes[0].hysteresis = sim::HysteresisKind::none;
  const sim::Setpoint programme = sim::draw_profile(sim::ProfileKind::cycle, unit, 3, 2);
  sim::ChamberRun run = sim::simulate_unit(unit, programme, 4);
  const sim::LawRegressors states = sim::law_regressors(unit, programme, run.rate_hz);
  const auto names = sim::law_regressor_names();
  const auto index = [&](std::string_view name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const std::vector<double>& coil = states[0][index("dTc")];
  const std::vector<double>& coil_rate = states[0][index("coil_rate")];
  const auto column = [&](std::string_view name) -> std::vector<double>& {
    return run.columns.at(static_cast<std::size_t>(
        std::find(run.column_names.begin(), run.column_names.end(), name) - run.column_names.begin()));
  };
  std::vector<double>& gyro = column("gyro_x");
  std::vector<double>& drift = column("drift_x");
  ASSERT_EQ(coil_rate.size(), gyro.size());
  double largest = 0;
  for (std::size_t k = 0; k < gyro.size(); ++k) {
    const double extra = 0.6 * coil_rate[k] * std::tanh(coil_rate[k] / 0.05) + 0.02 * coil[k] * coil_rate[k];
    gyro[k] += extra, drift[k] += extra;
    largest = std::max(largest, std::abs(extra));
  }
  ASSERT_GT(largest, 0.3) << "°/h: the added response matters against the floor";

  const auto [first_cycle, calibration, held_out, floor] = fit_first_cycle(run);

  const Pipeline& pipeline = calibration.model.axes[0].pipeline;
  std::string terms;
  bool asymmetric = false, tempco = false;
  for (const auto& term : pipeline.terms) {
    terms += term.name() + " ";
    if (term.factors.size() != 2) continue;
    const FeatureAtom::Kind first = term.factors[0].atom.kind, second = term.factors[1].atom.kind;
    const bool rate = first == FeatureAtom::Kind::lag_rate || first == FeatureAtom::Kind::lag2_rate;
    asymmetric = asymmetric || (rate && second == FeatureAtom::Kind::direction);
    tempco = tempco || (first == FeatureAtom::Kind::lag || first == FeatureAtom::Kind::lag2) &&
                           (second == FeatureAtom::Kind::lag_rate || second == FeatureAtom::Kind::lag2_rate);
  }
  SCOPED_TRACE("x: " + terms);
  std::printf("x: held-out %.2f x floor; %s\n", held_out[0].mse_after / floor[0], terms.c_str());
  EXPECT_TRUE(asymmetric) << "the node's rate times its direction of travel";
  EXPECT_TRUE(tempco) << "the node's level times its rate";
  // The rate responses read the coil's lag (600 s behind the thermometer). The static map
  // may take a lead-lag node in the default's search (599 s with a 559 s lead: the map of a
  // nearly unlagged temperature, the rate terms making up the delay), which the next
  // cycle cannot tell from the coil's lag; it is held below by the held-out bound.
  double rate_lag = 0;
  for (const auto& term : pipeline.terms) {
    if (term.factors.size() == 1 && term.factors[0].atom.kind == FeatureAtom::Kind::lag_rate && rate_lag == 0) {
      rate_lag = term.factors[0].atom.tau;
    }
  }
  EXPECT_NEAR(rate_lag, 600, 150) << "s: the node's rate, the coil's";
  EXPECT_LT(held_out[0].mse_after / floor[0], 3.0) << "held-out MSE over the noise floor, next cycle";
}

// Development law 5, x: the thermometer on the first of two nodes, the coil 666 s behind
// it, a tanh static, rate terms and a turn-on transient; no hysteresis, no Shupe term.
// Scored by the pooled CV MSE of one cycle, the search took two lags in series (338 s and
// 315 s) with a Shupe term and a heating/cooling memory the law does not have, and missed a
// fast programme (2-3 °C/min, three times the training ramps) by 123x the floor. Scored by
// the typical block: single lags near 660 s, no memory, 3.3x.
TEST(ThermalNode, ScoresSetsByTheTypicalBlock) {
  const auto [training, other, floor] = law_axis(5, 0, sim::ProfileKind::fast);

  double ratio[2] = {0, 0}, delay[2] = {0, 0};
  for (const auto score : {FeatureSelectionOptions::CvScore::geometric, FeatureSelectionOptions::CvScore::pooled}) {
    const int k = score == FeatureSelectionOptions::CvScore::geometric ? 0 : 1;
    CalibrationOptions options;
    options.model = ModelKind::linear;
    options.terms = {"auto"};
    options.selection.other_channels = false;  // the own thermometer: the case at hand, and a third of the time
    options.selection.cv_score = score;
    const Calibration calibration = calibrate({training}, LogSpec{}, options);
    const AxisModel& axis = calibration.model.axes[0];
    EXPECT_EQ(axis.fit.feature_selection.value().cv_score, k == 0 ? "geometric_mean" : "pooled");
    ratio[k] = evaluate(calibration.model, {other}, 1800)[0].mse_after / floor;
    delay[k] = node_delay(axis.pipeline);
    std::printf("%s: node delay %.0f s, fast programme %.3g x floor; %s\n", k == 0 ? "typical block" : "pooled",
                delay[k], ratio[k], fmt::format("{}", fmt::join(axis.pipeline.term_names(), " ")).c_str());
  }
  EXPECT_NEAR(delay[0], 666, 100) << "s: the coil behind the thermometer";
  EXPECT_LT(ratio[0], 6.0) << "held-out MSE over the noise floor, fast programme settled 1800 s";
  EXPECT_LT(3 * ratio[0], ratio[1]) << "the pooled score no longer fails here: the test tests less";
}

// Stepwise on identified terms chooses among the terms themselves: no squares or products
// of hinges, which extrapolate as parabolas. On other terms it still offers them.
TEST(ThermalNode, StepwiseOnIdentifiedTermsOffersNoProducts) {
  const sim::UnitLaw unit = known_unit();
  const sim::ChamberRun run = sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 3, 1), 4);
  const ChamberLog log = sim::to_chamber_log(run);
  CalibrationOptions options;
  options.model = ModelKind::stepwise;
  options.terms = {"lag:700", "hinge:700:-10", "hinge:700:10", "lagrate:700", "rate"};
  for (const bool identified : {true, false}) {
    options.partially_linear = identified;
    const Calibration calibration = calibrate({log}, LogSpec{}, options);
    bool products = false;
    for (const auto& axis : calibration.model.axes) {
      const auto& linear = std::get<LinearModel>(axis.model);
      for (const auto& regressor : linear.regressors) {
        int degree = 0;
        for (const int power : regressor.powers) degree += power;
        products = products || degree > 1;
      }
    }
    EXPECT_EQ(products, !identified) << (identified ? "identified terms" : "given terms");
  }
}

}  // namespace
}  // namespace thermodrift
