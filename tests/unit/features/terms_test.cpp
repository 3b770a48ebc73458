// Feature terms against closed forms: the exact step response of a first-order lag, the
// steady lag of a ramp, equilibrium at every (re)start, and the parser's round trip and
// refusals.
#include "thermodrift/features/terms.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

std::vector<FeatureTerm> parse_all(const std::vector<std::string>& names) {
  std::vector<FeatureTerm> terms;
  for (const auto& name : names) terms.push_back(FeatureTerm::parse(name));
  return terms;
}

TEST(FeatureTerms, NamesRoundTrip) {
  for (const std::string name : {"dT", "rate", "lag:600", "lagrate:420", "gradrate:420:240", "dir:900",
                                 "dir:900:420", "dir:900:420:0.07", "dir:900:0:0.5", "dT^2", "dT*rate", "lag:600^2*rate", "lag:12.5", "x3", "grad:1-4",
                                 "gradrate:12-3", "grad:2-1*lag:600", "hinge:600:-12.5", "hinge:600:0", "hinge:60:3*rate", "lead:900",
                                 "leadhinge:900:-3.5", "lag2:600:120", "lag2rate:600:120", "nodehinge:600:120:0:-3.5",
                                 "nodehinge:600:0:1800:12", "nodehinge:600:120:900:0*rate", "play:600:1.5",
                                 "play:600:0.25*rate", "on:300", "on:450*lag:600"}) {
    EXPECT_EQ(FeatureTerm::parse(name).name(), name);
  }
  const auto term = FeatureTerm::parse("gradrate:420:240");
  ASSERT_EQ(term.factors.size(), 1u);
  EXPECT_EQ(term.factors[0].atom.kind, FeatureAtom::Kind::gradient_rate);
  EXPECT_EQ(term.factors[0].atom.tau, 420);
  EXPECT_EQ(term.factors[0].atom.tau2, 240);
  EXPECT_TRUE(FeatureTerm::parse("rate").is_atom(FeatureAtom::Kind::rate));
  EXPECT_FALSE(FeatureTerm::parse("rate^2").is_atom(FeatureAtom::Kind::rate));
}

TEST(FeatureTerms, MalformedTermsAreUsageErrorsNamingTheTerm) {
  for (const std::string bad : {"", "lag", "lag:", "lag:0", "lag:-5", "lag:abc", "lag:1e7", "lag:nan", "lag:300:2",
                                "gradrate:400", "dir", "dir:1:2:3:4", "dir:1:2:0", "dir:1:2:nan",
                                "dir:1:2:1e9", "dir:1:-2:0.2", "dir:1:x:0.2", "dT^5", "dT^0", "dT^2^2", "dT^", "foo", "dT*",
                                "x0", "x3^2", "x3*dT", "rate:60", "grad", "grad:1", "grad:1-1", "grad:0-2", "grad:1-65",
                                "grad:a-b", "grad:1-2-3", "gradrate:1-", "grad:1-2:3", "grad:-1-2", "grad:001-2",
                                "hinge", "hinge:600", "hinge:0:5", "hinge:600:x", "hinge:600:nan", "hinge:600:1e9",
                                "hinge:600:1:2", "lead", "lead:0", "lead:5:5", "leadhinge:5", "leadhinge:0:1",
                                "lag2:600", "lag2:600:0", "lag2:0:5", "lag2rate:600", "lag2rate:600:-1",
                                "nodehinge:600:0:0", "nodehinge:0:0:0:1", "nodehinge:600:-1:0:1",
                                "nodehinge:600:0:x:1", "nodehinge:600:0:0:nan", "nodehinge:600:0:0:1:2",
                                "play", "play:600", "play:600:0", "play:600:-1", "play:0:1", "play:600:1e9",
                                "play:600:1:2", "on", "on:0", "on:-5", "on:300:2", "on:x"}) {
    try {
      FeatureTerm::parse(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const UsageError& error) {
      EXPECT_NE(std::string(error.what()).find("'" + bad + "'"), std::string::npos) << error.what();
    }
  }
}

// A first-order lag fed a held input is exact at any step: after a unit step at t = 0 it
// reads 1 - exp(-t/TAU) at every sample, however unevenly the samples fall.
TEST(FeatureTerms, LagIsExactForAStepWhateverTheSampling) {
  const double tau = 300;
  const auto terms = parse_all({"lag:300", "lagrate:300"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(2);
  evaluator.push(0, 0, 0, values);  // equilibrium at 0
  EXPECT_EQ(values[0], 0);
  EXPECT_EQ(values[1], 0);
  double t = 0;
  for (const double step : {0.1, 7.0, 33.3, 1.0, 250.0, 0.01, 600.0, 12.0}) {
    t += step;
    evaluator.push(1.0, 0, step, values);
    const double expected = 1 - std::exp(-t / tau);
    EXPECT_NEAR(values[0], expected, 1e-14) << "t = " << t;
    EXPECT_NEAR(values[1], (1 - expected) / tau * 60, 1e-14) << "t = " << t;  // °C/min
  }
}

// With the input held along a straight line between samples, a lag is exact for a ramp
// at any step: from equilibrium at 0, u = s·t gives L = s·(t - TAU·(1 - exp(-t/TAU))),
// and the memory's filter and the Shupe term's second lag are lags too. The step hold
// reads the ramp's later sample over the whole step, so it leads the ramp.
TEST(FeatureTerms, LinearHoldIsExactForARampWhateverTheSampling) {
  const double tau = 300, slope = 0.02;  // °C/s
  const auto terms = parse_all({"lag:300", "lagrate:300"});
  TermEvaluator linear(terms, InputHold::linear), step(terms);
  std::vector<double> values(2), stepped(2);
  linear.push(0, 0, 0, values);
  step.push(0, 0, 0, stepped);
  double t = 0;
  for (const double h : {0.1, 7.0, 33.3, 1.0, 250.0, 0.01, 600.0, 12.0}) {
    t += h;
    linear.push(slope * t, 0, h, values);
    step.push(slope * t, 0, h, stepped);
    const double expected = slope * (t - tau * (1 - std::exp(-t / tau)));
    EXPECT_NEAR(values[0], expected, 1e-12) << "t = " << t;
    EXPECT_NEAR(values[1], (slope * t - expected) / tau * 60, 1e-12) << "t = " << t;
  }
  EXPECT_GT(stepped[0] - slope * (t - tau * (1 - std::exp(-t / tau))), 1e-3);
}

// on:TAU is exp(-t/TAU), t counted from the last (re)start, at any sampling, whatever
// the temperature does; a step of 0 (a gap) starts it again at 1.
TEST(FeatureTerms, TurnOnDecaysFromEachRestart) {
  const auto terms = parse_all({"on:300", "on:450*dT"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(2);
  evaluator.push(2.0, 0.5, 0, values);
  EXPECT_EQ(values[0], 1);
  EXPECT_EQ(values[1], 2.0);
  double t = 0;
  for (const double step : {0.1, 7.0, 33.3, 1.0, 250.0, 0.01, 600.0, 12.0}) {
    t += step;
    evaluator.push(-1.5 + t / 100, 3.0, step, values);
    EXPECT_NEAR(values[0], std::exp(-t / 300), 1e-14) << "t = " << t;
    EXPECT_NEAR(values[1], std::exp(-t / 450) * (-1.5 + t / 100), 1e-13) << "t = " << t;
  }
  evaluator.push(4.0, 0, 0, values);
  EXPECT_EQ(values[0], 1);
  evaluator.push(4.0, 0, 30, values);
  EXPECT_NEAR(values[0], std::exp(-30.0 / 300), 1e-15);
}

// On a ramp r the discrete lag settles r·h·a/(1 - a) behind the input (a = exp(-h/TAU)),
// which is TAU·r to first order in h/TAU; lagrate then reads the ramp's rate, the
// gradient's rate settles to 0, and the direction memory to tanh(rate / R0), R0 = 0.2 °C/min
// unless the term gives its own.
TEST(FeatureTerms, RampSettlesToItsClosedForm) {
  const double tau = 400, h = 5, r = 0.5 / 60;  // °C/s: 0.5 °C/min
  const double a = std::exp(-h / tau);
  const double behind = r * h * a / (1 - a);
  const auto terms =
      parse_all({"lag:400", "lagrate:400", "gradrate:400:200", "dir:300", "dir:300:400", "dir:300:0:0.5", "dir:300:400:1.5"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(terms.size());
  for (int k = 0; k <= 20000; ++k) {  // 250 TAU
    evaluator.push(r * k * h, r * 60, k == 0 ? 0 : h, values);
  }
  const double t = 20000 * h;
  EXPECT_NEAR(values[0], r * t - behind, 1e-9);
  EXPECT_NEAR(behind, r * tau, r * h);
  EXPECT_NEAR(values[1], behind / tau * 60, 1e-9);
  EXPECT_NEAR(values[1], r * 60, r * 60 * h / tau);
  EXPECT_NEAR(values[2], 0, 1e-9);
  EXPECT_NEAR(values[3], std::tanh(r * 60 / kDirectionRateScale), 1e-12);
  EXPECT_NEAR(values[4], std::tanh(values[1] / kDirectionRateScale), 1e-9);
  EXPECT_NEAR(values[5], std::tanh(r * 60 / 0.5), 1e-12);
  EXPECT_NEAR(values[6], std::tanh(values[1] / 1.5), 1e-9);
  EXPECT_GT(values[3] - values[5], 0.1);  // the scale is used, not the default
}

// A step of 0 is a (re)start: every state goes to equilibrium with the current input, so a
// log that resumes after a gap does not carry a stale coil temperature across it.
TEST(FeatureTerms, RestartSetsEveryStateInEquilibrium) {
  const auto terms = parse_all({"lag:600", "lagrate:600", "gradrate:600:300", "dir:900", "dT", "rate"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(terms.size());
  for (int k = 0; k < 100; ++k) evaluator.push(0.1 * k, 6, k == 0 ? 0 : 60, values);
  EXPECT_NEAR(values[1], 0.1, 0.01);  // following the 0.1 °C/min ramp
  evaluator.push(-3.0, -0.4, 0, values);
  EXPECT_EQ(values[0], -3.0);
  EXPECT_EQ(values[1], 0);
  EXPECT_EQ(values[2], 0);
  EXPECT_NEAR(values[3], std::tanh(-0.4 / kDirectionRateScale), 1e-15);
  EXPECT_EQ(values[4], -3.0);
  EXPECT_EQ(values[5], -0.4);
}

// grad:A-B and gradrate:A-B are differences of the channels' smoothed values and rates,
// whatever else the sample holds; a channel the inputs lack is a UsageError.
TEST(FeatureTerms, ChannelGradientsAreDifferencesOfTheChannels) {
  const auto terms = parse_all({"grad:1-3", "gradrate:3-2", "grad:2-1^2", "dT"});
  EXPECT_EQ(terms[0].channels(), (std::vector<std::size_t>{0, 2}));
  EXPECT_EQ(terms[1].factors[0].atom.kind, FeatureAtom::Kind::channel_gradient_rate);
  TermEvaluator evaluator(terms);
  std::vector<double> values(terms.size());
  const std::vector<double> means = {21.5, 20.25, 18.0};
  const std::vector<double> rates = {0.4, -0.1, 0.7};
  evaluator.push(TermInputs{3.0, 0.2, 1.0, means, rates}, values);
  EXPECT_EQ(values[0], 21.5 - 18.0);
  EXPECT_EQ(values[1], 0.7 - -0.1);
  EXPECT_EQ(values[2], (20.25 - 21.5) * (20.25 - 21.5));
  EXPECT_EQ(values[3], 3.0);
  const std::vector<double> two = {1, 2};
  EXPECT_THROW(evaluator.push(TermInputs{0, 0, 1, two, two}, values), UsageError);
  EXPECT_THROW(evaluator.push(0, 0, 1, values), UsageError);
}

// A product is the product of its atoms' streams, each with its own state.
// hinge:TAU:K is max(0, L - K) of the lag L its own filter keeps: zero below the knot, the
// lag minus the knot above it, at every sample of a ramp through the knot.
TEST(FeatureTerms, HingeIsTheLagAboveItsKnot) {
  const auto terms = parse_all({"lag:300", "hinge:300:2", "hinge:300:-1"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(3);
  double crossed = 0;
  for (int k = 0; k <= 2000; ++k) {
    const double delta_t = -3.0 + 0.005 * k;  // -3 .. 7 °C over 2000 s
    evaluator.push(delta_t, 0.3, k == 0 ? 0.0 : 1.0, values);
    EXPECT_DOUBLE_EQ(values[1], std::max(0.0, values[0] - 2.0)) << k;
    EXPECT_DOUBLE_EQ(values[2], std::max(0.0, values[0] + 1.0)) << k;
    if (values[1] > 0 && crossed == 0) crossed = k;
  }
  EXPECT_GT(crossed, 0);  // the lag did cross the upper knot
}

// lead:TAU undoes a first-order lag: on a ramp r after the transient a sensor lagging by TAU
// reads r·TAU low, and lead adds exactly that back (rate in °C/min, TAU in s).
TEST(FeatureTerms, LeadAddsBackTheLagOfARamp) {
  const auto terms = parse_all({"lead:600", "leadhinge:600:10"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(2);
  const double rate = 1.5;  // °C/min
  for (const double delta_t : {-4.0, 2.0, 9.0}) {
    evaluator.push(delta_t, rate, 1.0, values);
    EXPECT_DOUBLE_EQ(values[0], delta_t + 600 * rate / 60.0);
    EXPECT_DOUBLE_EQ(values[1], std::max(0.0, values[0] - 10.0));
  }
}

// lag2:T1:T2 is two first-order lags in series. On a ramp r from equilibrium its closed
// form is L2 = r·(t - T1 - T2) + r·(T1²·e^(-t/T1) - T2²·e^(-t/T2)) / (T1 - T2). Each filter
// step holds the step's last input over it, which puts a lag about half a step ahead of a
// ramp: the pair is checked to one step's rise, r·1 s. lag2rate is checked against the
// states' own difference and nodehinge against L2 + TL·dL2/dt through its knot.
TEST(FeatureTerms, SeriesLagsFollowTheirClosedFormOnARamp) {
  const double t1 = 400, t2 = 150, lead = 900, knot = 3;
  const auto terms = parse_all({"lag2:400:150", "lag2rate:400:150", "nodehinge:400:150:900:3", "lag:400"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(4);
  const double r = 1.0 / 60.0;  // °C/s
  bool crossed = false;
  for (int k = 0; k <= 3000; ++k) {
    const double t = k;
    evaluator.push(r * t, 60 * r, k == 0 ? 0.0 : 1.0, values);
    const double exact = r * (t - t1 - t2) + r * (t1 * t1 * std::exp(-t / t1) - t2 * t2 * std::exp(-t / t2)) / (t1 - t2);
    EXPECT_NEAR(values[0], exact, r * 1.0) << t;
    if (k > 0) EXPECT_GT(values[0], exact) << t;  // ahead of the ramp, never behind it
    const double l2_rate = (values[3] - values[0]) / t2 * 60.0;
    EXPECT_NEAR(values[1], l2_rate, 1e-12) << t;
    EXPECT_NEAR(values[2], std::max(0.0, values[0] + lead * l2_rate / 60.0 - knot), 1e-12) << t;
    crossed = crossed || values[2] > 0;
  }
  EXPECT_TRUE(crossed);
  EXPECT_NEAR(values[1], 60 * r * (1 - std::exp(-3000 / t2)), 2e-2);  // on the ramp's rate
}

// nodehinge with T2 = 0 is a lead-lag of one pole: L1 + TL·dL1/dt. With TL = T1 it undoes
// the lag exactly (the node is ΔT itself), and with TL = 0 it is hinge:T1:K.
TEST(FeatureTerms, NodeHingeOfOnePoleIsALeadLag) {
  const auto terms = parse_all({"nodehinge:300:0:300:-100", "nodehinge:300:0:0:2", "hinge:300:2"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(3);
  for (int k = 0; k <= 2000; ++k) {
    const double delta_t = 5 * std::sin(k / 300.0);
    evaluator.push(delta_t, 0, k == 0 ? 0.0 : 1.0, values);
    EXPECT_NEAR(values[0] - 100, delta_t, 1e-9) << k;
    EXPECT_DOUBLE_EQ(values[1], values[2]) << k;
  }
}

// play:TAU:W is the backlash of the node: +1 after the node rose by more than 2W, -1 after
// it fell by that much, and in between after a turn it moves one for one with the node
// ((L - P)/W with P held). A lag of 1 s sampled every 10 s is the input to 5e-5 °C.
TEST(FeatureTerms, PlayIsTheBacklashOfTheNode) {
  const auto terms = parse_all({"play:1:1", "play:1:2"});
  TermEvaluator evaluator(terms);
  std::vector<double> values(2);
  evaluator.push(0.0, 0, 0, values);
  EXPECT_EQ(values[0], 0);  // a start is equilibrium: the play sits on the node
  for (double t = 0.5; t <= 5.0; t += 0.5) evaluator.push(t, 0, 10, values);  // up 5 °C
  EXPECT_NEAR(values[0], 1.0, 1e-3);
  EXPECT_NEAR(values[1], 1.0, 1e-3);
  evaluator.push(4.0, 0, 10, values);  // a turn of 1 °C: inside both bands
  EXPECT_NEAR(values[0], 0.0, 1e-3);
  EXPECT_NEAR(values[1], 0.5, 1e-3);
  evaluator.push(2.5, 0, 10, values);  // 2.5 °C below the top: through the narrow band only
  EXPECT_NEAR(values[0], -1.0, 1e-3);
  EXPECT_NEAR(values[1], -0.25, 1e-3);
  evaluator.push(3.0, 0, 10, values);  // back up 0.5 °C: both hold their new play
  EXPECT_NEAR(values[0], -0.5, 1e-3);
  EXPECT_NEAR(values[1], 0.0, 1e-3);
  evaluator.push(3.0, 0, 0, values);  // a restart: equilibrium again
  EXPECT_EQ(values[0], 0);
  EXPECT_EQ(values[1], 0);
}

TEST(FeatureTerms, ProductsAndPowersMultiplyTheAtoms) {
  const auto atoms = parse_all({"lag:300", "rate", "dir:200"});
  const auto products = parse_all({"lag:300^2*rate", "dir:200*lag:300", "rate^3"});
  TermEvaluator atom_evaluator(atoms), product_evaluator(products);
  std::vector<double> a(3), p(3);
  for (int k = 0; k < 500; ++k) {
    const double t = 10.0 * k;
    const double delta_t = 5 * std::sin(t / 2000), rate = 0.15 * std::cos(t / 2000) * 60 / 2000 * 60;
    atom_evaluator.push(delta_t, rate, k == 0 ? 0 : 10, a);
    product_evaluator.push(delta_t, rate, k == 0 ? 0 : 10, p);
    EXPECT_DOUBLE_EQ(p[0], a[0] * a[0] * a[1]);
    EXPECT_DOUBLE_EQ(p[1], a[2] * a[0]);
    EXPECT_DOUBLE_EQ(p[2], a[1] * a[1] * a[1]);
  }
}

// Terms that share a filter (a node's level, hinges and rate; two lags in series and their
// node; plays and memories on the same lag) are stepped once per sample and read off it, and
// samples whose values are not wanted only advance the filters. Both must leave every value
// bit for bit what each term gives alone, pushed at every sample, through uneven steps and
// restarts.
TEST(FeatureTerms, SharedFiltersAndSkippedSamplesChangeNoValue) {
  const std::vector<std::string> names{"lag:600", "hinge:600:-2", "hinge:600:3", "lagrate:600", "lag2:600:120",
                                       "nodehinge:600:120:0:1", "lag2rate:600:120", "nodehinge:600:120:900:-1",
                                       "nodehinge:600:0:300:0.5", "lag2:600:240", "play:600:1", "dir:900:600",
                                       "gradrate:600:120", "lag:600^2*rate", "on:300", "dir:400", "rate", "dT",
                                       "nodehinge:300:0:0:2", "lag:300*hinge:600:0"};
  const auto terms = parse_all(names);
  TermEvaluator together(terms);
  std::vector<std::vector<FeatureTerm>> single;
  for (const auto& term : terms) single.push_back({term});
  std::vector<TermEvaluator> alone;
  for (const auto& one : single) alone.emplace_back(one);
  std::vector<double> values(terms.size()), value(1);
  int compared = 0;
  for (int k = 0; k < 3000; ++k) {
    const double step = k == 0 || k == 1700 ? 0 : (k % 7 == 0 ? 2.5 : 1.0);
    const double delta_t = 8 * std::sin(k / 300.0) + 0.01 * (k % 13), rate = 1.6 * std::cos(k / 300.0);
    const bool wanted = k % 10 == 0 || (k > 1690 && k < 1710);
    if (wanted) {
      together.push(delta_t, rate, step, values);
    } else {
      together.advance(TermInputs{delta_t, rate, step, {}, {}});
    }
    for (std::size_t j = 0; j < terms.size(); ++j) {
      alone[j].push(delta_t, rate, step, value);
      if (!wanted) continue;
      ASSERT_EQ(values[j], value[0]) << names[j] << " at sample " << k;
      ++compared;
    }
  }
  EXPECT_EQ(compared, static_cast<int>(terms.size()) * (300 + 19 - 1));  // sample 1700 counted once
}

}  // namespace
}  // namespace thermodrift
