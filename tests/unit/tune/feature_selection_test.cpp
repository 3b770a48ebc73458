// --features auto against logs whose drift law is known: a coil lagging the sensor by a
// known time constant must be found (terms and constant), and a plain ΔT law must not
// collect terms that do not pay.
#include "thermodrift/tune/feature_selection.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "../../support/fitted_model.hpp"
#include "thermodrift/features/terms.hpp"

namespace thermodrift {
namespace {

// Chamber-like sensor temperature at 1 Hz: soaks and 0.8 °C/min ramps between -10 and
// 40 °C, with the gyro given by `drift(ΔT, values of truth_terms)` of the raw temperature
// plus white noise of 0.5 °/h.
template <class Drift>
ChamberLog synthetic_log(const std::vector<std::string>& truth_terms, Drift drift) {
  ChamberLog log;
  log.source = "synthetic";
  log.gyro_names = {"gyro"};
  log.temperature_names = {"temp"};
  log.gyro.resize(1);
  log.temperature.resize(1);
  const std::vector<std::pair<double, double>> corners = {{0, 15},     {3600, 15},   {6975, 40},  {12375, 40},
                                                          {18000, -10}, {23400, -10}, {27000, 20}, {32000, 20}};
  std::vector<FeatureTerm> terms;
  for (const auto& name : truth_terms) terms.push_back(FeatureTerm::parse(name));
  TermEvaluator evaluator(terms);
  std::vector<double> values(terms.size());
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::size_t piece = 0;
  double previous = 15;
  for (int t = 0; t <= 32000; ++t) {
    while (corners[piece + 1].first < t) ++piece;
    const auto [t0, c0] = corners[piece];
    const auto [t1, c1] = corners[piece + 1];
    const double temperature = c0 + (c1 - c0) * (t - t0) / (t1 - t0);
    evaluator.push(temperature - 15, (temperature - previous) * 60.0, t == 0 ? 0 : 1, values);
    previous = temperature;
    log.time.push_back(t);
    log.temperature[0].push_back(temperature);
    log.gyro[0].push_back(drift(temperature - 15, values) + noise(random));
  }
  return log;
}

template <class Drift>
ChamberLog synthetic_log(double tau, Drift drift) {
  return synthetic_log({fmt::format("lag:{}", tau), fmt::format("lagrate:{}", tau)},
                       [&](double delta_t, const std::vector<double>& v) { return drift(delta_t, v[0], v[1]); });
}

// The time constant of the first atom of `kind` in `terms`, or 0.
double time_constant_of(const std::vector<std::string>& terms, FeatureAtom::Kind kind, bool second = false) {
  for (const auto& name : terms) {
    for (const auto& factor : FeatureTerm::parse(name).factors) {
      if (factor.atom.kind == kind) return second ? factor.atom.tau2 : factor.atom.tau;
    }
  }
  return 0;
}

Pipeline synthetic_pipeline() { return testing::chamber_pipeline(15); }

constexpr double kSmoothedNoiseVariance = 0.25 / 100;  // white 0.5 °/h through a 100-sample mean

// A coil 600 s behind the sensor, drifting with its temperature and its rate: the search
// finds a lag near 600 s and gets close to the noise, where ΔT and rate cannot.
TEST(FeatureSelection, FindsTheCoilLagAndItsTimeConstant) {
  const auto log = synthetic_log(600, [](double, double lag, double lag_rate) {
    return 0.08 * lag + 4.0 * lag_rate + 0.002 * lag * lag;
  });
  const FeatureSelection chosen = select_features({log}, 0, synthetic_pipeline(), FeatureSelectionOptions{});
  std::string names;
  for (const auto& term : chosen.terms) names += term + " ";
  bool found_lag = false;
  for (const auto& name : chosen.terms) {
    for (const auto& factor : FeatureTerm::parse(name).factors) {
      const auto kind = factor.atom.kind;
      if ((kind == FeatureAtom::Kind::lag || kind == FeatureAtom::Kind::lag_rate) && factor.atom.tau >= 510 &&
          factor.atom.tau <= 690) {
        found_lag = true;
      }
    }
  }
  EXPECT_TRUE(found_lag) << names;
  EXPECT_LT(chosen.cv_mse, 3 * kSmoothedNoiseVariance) << names;
  EXPECT_LT(chosen.cv_mse, 1e-3 * chosen.start_mse) << names;
  ASSERT_FALSE(chosen.path.empty());
  EXPECT_EQ(chosen.path.back().terms, chosen.terms);
  // The paper's pair on the same data, scored the same way, stays far above.
  FeatureSelectionOptions seed_only;
  seed_only.max_terms = 0;
  EXPECT_EQ(select_features({log}, 0, synthetic_pipeline(), seed_only).terms, (std::vector<std::string>{"dT", "rate"}));
}

// A drift that is ΔT alone: dT first, and the penalty stops the search soon after.
TEST(FeatureSelection, PenaltyKeepsAPlainLawPlain) {
  const auto log = synthetic_log(600, [](double delta_t, double, double) { return 0.1 * delta_t; });
  const FeatureSelection chosen = select_features({log}, 0, synthetic_pipeline(), FeatureSelectionOptions{});
  ASSERT_FALSE(chosen.terms.empty());
  EXPECT_EQ(chosen.path.front().term, "dT");
  EXPECT_LE(chosen.terms.size(), 2u);
  EXPECT_LT(chosen.cv_mse, 1.5 * kSmoothedNoiseVariance);
  // The path is the record of the search: each addition and each move lowers the score.
  double previous = chosen.start_mse;
  for (const auto& step : chosen.path) {
    if (step.action == "drop") {  // may cost up to the penalty
      EXPECT_LT(step.cv_mse, previous / (1 - FeatureSelectionOptions{}.min_gain)) << step.term;
      previous = step.cv_mse;
      continue;
    }
    EXPECT_LT(step.cv_mse, previous) << step.term;
    previous = step.cv_mse;
  }
}

// The IEEE 952 terms on a coil 600 s behind the sensor — its temperature, rate and the
// rate of a gradient lagging that rate by 240 s — plus a heating/cooling memory of 900 s.
// The gradient and hysteresis terms each pay little alone at the right lag (moving the
// lag pays more), so a plain greedy search settles on a wrong lag; the search must find
// all three time constants.
TEST(FeatureSelection, FindsShupeAndHysteresisTermsOnTheCoilLag) {
  const std::vector<std::string> truth = {"lag:600", "lagrate:600", "gradrate:600:240", "dir:900:600"};
  const auto log = synthetic_log(truth, [](double, const std::vector<double>& v) {
    return 0.05 * v[0] + 1.5 * v[1] + 12.0 * v[2] + 0.4 * v[3];
  });
  const FeatureSelection chosen = select_features({log}, 0, synthetic_pipeline(), FeatureSelectionOptions{});
  std::string names;
  for (const auto& term : chosen.terms) names += term + " ";
  using Kind = FeatureAtom::Kind;
  EXPECT_NEAR(time_constant_of(chosen.terms, Kind::lag), 600, 60) << names;
  EXPECT_NEAR(time_constant_of(chosen.terms, Kind::gradient_rate), 600, 60) << names;
  EXPECT_NEAR(time_constant_of(chosen.terms, Kind::gradient_rate, true), 240, 50) << names;
  EXPECT_NEAR(time_constant_of(chosen.terms, Kind::direction), 900, 250) << names;
  EXPECT_LT(chosen.cv_mse, 1.3 * kSmoothedNoiseVariance) << names;
}

// A second temperature channel that no term of the first can rebuild (a mount following
// its own slow cycle) and a drift on the difference of the two: the search offers
// grad:1-2 and takes it.
TEST(FeatureSelection, TakesTheGradientToASecondChannelWhenItPays) {
  ChamberLog log = synthetic_log(600, [](double, double, double) { return 0.0; });
  log.temperature_names.push_back("temp_mount");
  log.temperature.emplace_back();
  std::mt19937_64 random(11);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (std::size_t i = 0; i < log.rows(); ++i) {
    const double sensor = log.temperature[0][i];
    const double mount = 12 + 6 * std::sin(log.time[i] / 4000.0);
    log.temperature[1].push_back(mount);
    log.gyro[0][i] = 0.05 * (sensor - 15) + 0.4 * (sensor - mount) + noise(random);
  }
  EXPECT_EQ(channel_candidate_terms(log, 0), (std::vector<std::string>{"grad:1-2", "gradrate:1-2"}));
  const FeatureSelection chosen = select_features({log}, 0, synthetic_pipeline(), FeatureSelectionOptions{});
  std::string names;
  for (const auto& term : chosen.terms) names += term + " ";
  EXPECT_NE(std::find(chosen.terms.begin(), chosen.terms.end(), "grad:1-2"), chosen.terms.end()) << names;
  EXPECT_LT(chosen.cv_mse, 1.3 * kSmoothedNoiseVariance) << names;
  // One channel: nothing to take a gradient to.
  EXPECT_TRUE(channel_candidate_terms(synthetic_log(600, [](double, double, double) { return 0.0; }), 0).empty());
}

// judge_by_svr keeps one of the sets the search settled on, records each it judged, and
// reports the SVR's CV MSE of the one it kept.
TEST(FeatureSelection, SvrJudgesTheSetsTheSearchSettledOn) {
  const auto log = synthetic_log(600, [](double, double lag, double lag_rate) {
    return 0.08 * lag + 4.0 * lag_rate + 0.002 * lag * lag;
  });
  FeatureSelection chosen = select_features({log}, 0, synthetic_pipeline(), FeatureSelectionOptions{});
  const auto searched = chosen.path;
  SvrJudgeOptions judge;
  judge.tuning = SvrTuningOptions{};
  judge.evaluations = 8;
  judge_by_svr(chosen, {log}, 0, synthetic_pipeline(), judge);
  EXPECT_EQ(chosen.scored_by, "least_squares+svr");
  ASSERT_GT(chosen.path.size(), searched.size());
  bool kept_a_judged_set = false;
  for (std::size_t i = searched.size(); i < chosen.path.size(); ++i) {
    const auto& step = chosen.path[i];
    EXPECT_EQ(step.action, "svr");
    const bool from_search = std::any_of(searched.begin(), searched.end(),
                                         [&](const SelectionStep& s) { return s.terms == step.terms; });
    EXPECT_TRUE(from_search) << step.term;
    if (step.terms == chosen.terms) kept_a_judged_set = step.cv_mse == chosen.cv_mse;
  }
  EXPECT_TRUE(kept_a_judged_set);
  EXPECT_LE(chosen.path.size() - searched.size(), judge.sets);
  // An SVR on the coil lag gets near the noise too (it has the same information).
  EXPECT_LT(chosen.cv_mse, 3 * kSmoothedNoiseVariance);
}

}  // namespace
}  // namespace thermodrift
