// Least squares against the closed-form normal-equation solution, stepwise selection on a
// known law, and rank deficiency.
#include "thermodrift/models/linear.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "thermodrift/error.hpp"
#include "thermodrift/models/metrics.hpp"

namespace thermodrift {
namespace {

// Deterministic uniform and normal numbers, the same on every platform.
struct Random {
  std::uint64_t state;
  explicit Random(std::uint64_t seed) : state(seed * 0x9E3779B97F4A7C15ull + 1) {}
  double uniform() {  // (0, 1)
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return (static_cast<double>(state >> 11) + 0.5) * 0x1.0p-53;
  }
  double normal() {  // Box-Muller
    return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2.0 * std::numbers::pi * uniform());
  }
};

// [1, x1, ..., xd] for a plain linear model.
Eigen::MatrixXd with_intercept(const Eigen::MatrixXd& features) {
  Eigen::MatrixXd design(features.rows(), features.cols() + 1);
  design.col(0).setOnes();
  design.rightCols(features.cols()) = features;
  return design;
}

// The closed-form answer, β = (XᵀX)⁻¹Xᵀy, independently of the QR code under test.
Eigen::VectorXd normal_equations(const Eigen::MatrixXd& design, const Eigen::VectorXd& target) {
  return (design.transpose() * design).ldlt().solve(design.transpose() * target);
}

struct Problem {
  Eigen::MatrixXd features;
  Eigen::VectorXd target;
};

// A chamber-like, well-conditioned problem: ΔT over ±40 °C, rate over ±1 °C/min.
Problem chamber_like(std::size_t n, std::uint64_t seed) {
  Random random(seed);
  Problem problem{Eigen::MatrixXd(n, 2), Eigen::VectorXd(n)};
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(n); ++i) {
    const double dT = 80.0 * random.uniform() - 40.0;
    const double rate = 2.0 * random.uniform() - 1.0;
    problem.features(i, 0) = dT;
    problem.features(i, 1) = rate;
    problem.target(i) = 0.5 + 0.03 * dT + 1.2 * rate + 4e-4 * dT * dT + 0.05 * random.normal();
  }
  return problem;
}

double relative_difference(double a, double b) { return std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

TEST(FitLeastSquares, MatchesTheNormalEquationSolution) {
  const Problem problem = chamber_like(2000, 1);
  const LinearModel model = fit_least_squares(problem.features, problem.target, linear_regressors(2));
  const Eigen::VectorXd beta = normal_equations(with_intercept(problem.features), problem.target);
  EXPECT_EQ(model.rank_deficiency, 0u);
  ASSERT_EQ(model.coefficients.size(), 2);
  EXPECT_LT(relative_difference(model.intercept, beta(0)), 1e-8);
  EXPECT_LT(relative_difference(model.coefficients(0), beta(1)), 1e-8);
  EXPECT_LT(relative_difference(model.coefficients(1), beta(2)), 1e-8);
}

TEST(FitLeastSquares, QuadraticRegressorsMatchTheNormalEquationSolution) {
  const Problem problem = chamber_like(3000, 2);
  const auto regressors = quadratic_regressors(2);  // dT, rate, dT², dT·rate, rate²
  ASSERT_EQ(regressors.size(), 5u);
  Eigen::MatrixXd design(problem.features.rows(), 6);
  for (Eigen::Index i = 0; i < design.rows(); ++i) {
    const double dT = problem.features(i, 0), rate = problem.features(i, 1);
    design.row(i) << 1.0, dT, rate, dT * dT, dT * rate, rate * rate;
  }
  const LinearModel model = fit_least_squares(problem.features, problem.target, regressors);
  const Eigen::VectorXd beta = normal_equations(design, problem.target);
  EXPECT_LT(relative_difference(model.intercept, beta(0)), 1e-8);
  for (Eigen::Index k = 0; k < 5; ++k) {
    EXPECT_LT(relative_difference(model.coefficients(k), beta(k + 1)), 1e-8) << "regressor " << k;
  }
}

TEST(FitLeastSquares, ResidualIsOrthogonalToEveryRegressor) {
  const Problem problem = chamber_like(1500, 3);
  const auto regressors = quadratic_regressors(2);
  const LinearModel model = fit_least_squares(problem.features, problem.target, regressors);
  const Eigen::VectorXd residual = problem.target - model.predict(problem.features);
  EXPECT_NEAR(residual.sum(), 0.0, 1e-9 * residual.norm() * std::sqrt(1500.0));  // the intercept's column
  std::vector<double> row(2);
  for (const auto& regressor : regressors) {
    Eigen::VectorXd column(problem.features.rows());
    for (Eigen::Index i = 0; i < column.size(); ++i) {
      row = {problem.features(i, 0), problem.features(i, 1)};
      column(i) = regressor.evaluate(row);
    }
    EXPECT_LT(std::abs(column.dot(residual)), 1e-10 * column.norm() * residual.norm())
        << regressor.name({"dT", "rate"});
  }
}

TEST(FitLeastSquares, ExactDataIsRecoveredExactly) {
  Eigen::MatrixXd features(5, 1);
  features << -2, -1, 0, 1, 2;
  const Eigen::VectorXd target = (3.0 - 0.5 * features.col(0).array()).matrix();
  const LinearModel model = fit_least_squares(features, target, linear_regressors(1));
  EXPECT_NEAR(model.intercept, 3.0, 1e-12);
  EXPECT_NEAR(model.coefficients(0), -0.5, 1e-12);
  const std::vector<double> at = {4.0};
  EXPECT_NEAR(model.predict(at), 1.0, 1e-12);
}

TEST(FitLeastSquares, TooFewSamplesIsAUsageError) {
  const Problem problem = chamber_like(2, 4);
  EXPECT_THROW(fit_least_squares(problem.features, problem.target, linear_regressors(2)), UsageError);
}

TEST(FitLeastSquares, ConstantTemperatureIsRankDeficientButFinite) {
  // ΔT is the same on every row, so it is collinear with the intercept.
  Random random(5);
  const Eigen::Index n = 500;
  Eigen::MatrixXd features(n, 2);
  Eigen::VectorXd target(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    features(i, 0) = 3.5;
    features(i, 1) = 2.0 * random.uniform() - 1.0;
    target(i) = 2.0 + 1.5 * features(i, 1) + 0.01 * random.normal();
  }
  const LinearModel model = fit_least_squares(features, target, linear_regressors(2));
  EXPECT_EQ(model.rank_deficiency, 1u);
  EXPECT_TRUE(std::isfinite(model.intercept));
  EXPECT_TRUE(model.coefficients.allFinite());
  // The fit is still the least-squares fit: the same predictions as without the ΔT column.
  const LinearModel rate_only = fit_least_squares(features.rightCols(1), target, linear_regressors(1));
  EXPECT_NEAR(model.coefficients(1), rate_only.coefficients(0), 1e-9);
  const Eigen::VectorXd difference = model.predict(features) - rate_only.predict(features.rightCols(1).eval());
  EXPECT_LT(difference.cwiseAbs().maxCoeff(), 1e-9);
  // One of the two collinear parameters is left at exactly 0.
  EXPECT_TRUE(model.intercept == 0.0 || model.coefficients(0) == 0.0)
      << "intercept " << model.intercept << ", dT " << model.coefficients(0);
}

TEST(FitLeastSquares, RankDecisionDoesNotDependOnUnits) {
  // ΔT in millikelvin-sized numbers and a tiny rate: both still count.
  Problem problem = chamber_like(800, 6);
  problem.features.col(0) *= 1e6;
  problem.features.col(1) *= 1e-6;
  const LinearModel model = fit_least_squares(problem.features, problem.target, linear_regressors(2));
  EXPECT_EQ(model.rank_deficiency, 0u);
  const Eigen::VectorXd beta = normal_equations(with_intercept(problem.features), problem.target);
  EXPECT_LT(relative_difference(model.coefficients(1), beta(2)), 1e-6);
}

// y = 1 + 2·ΔT + 0.5·ΔT² + noise, with rate as an irrelevant second term.
Problem quadratic_law(std::size_t n, std::uint64_t seed, double noise) {
  Random random(seed);
  Problem problem{Eigen::MatrixXd(n, 2), Eigen::VectorXd(n)};
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(n); ++i) {
    const double dT = 4.0 * random.uniform() - 2.0;
    const double rate = 2.0 * random.uniform() - 1.0;
    problem.features(i, 0) = dT;
    problem.features(i, 1) = rate;
    problem.target(i) = 1.0 + 2.0 * dT + 0.5 * dT * dT + noise * random.normal();
  }
  return problem;
}

TEST(FitStepwise, PicksDeltaTAndItsSquareOnly) {
  const std::vector<std::string> names = {"dT", "rate"};
  int runs = 0;
  for (std::uint64_t seed : {11u, 12u, 13u}) {
    const Problem problem = quadratic_law(400, seed, 0.05);
    const StepwiseFit fit = fit_stepwise(problem.features, problem.target, quadratic_regressors(2), names);
    std::vector<std::string> chosen;
    for (const auto& regressor : fit.model.regressors) chosen.push_back(regressor.name(names));
    std::sort(chosen.begin(), chosen.end());
    EXPECT_EQ(chosen, (std::vector<std::string>{"dT", "dT^2"})) << "seed " << seed;
    ASSERT_GE(fit.path.size(), 2u);
    EXPECT_EQ(fit.path[0].action, "add");
    EXPECT_EQ(fit.path[0].regressor, "dT");  // the strongest term enters first
    EXPECT_EQ(fit.path[1].regressor, "dT^2");
    for (const auto& step : fit.path) EXPECT_GT(step.f_statistic, 4.0);
    if (chosen.size() == 2) {
      const auto& model = fit.model;
      const std::size_t linear = model.regressors[0].name(names) == "dT" ? 0 : 1;
      EXPECT_NEAR(model.intercept, 1.0, 0.02);
      EXPECT_NEAR(model.coefficients(static_cast<Eigen::Index>(linear)), 2.0, 0.02);
      EXPECT_NEAR(model.coefficients(static_cast<Eigen::Index>(1 - linear)), 0.5, 0.02);
    }
    ++runs;
  }
  EXPECT_EQ(runs, 3);
}

// Each step's partial F, computed from the current fit's basis, is the F of refitting with
// the candidate added: checked against two least-squares fits at every "add".
TEST(FitStepwise, EachAddedRegressorsFIsThatOfARefit) {
  const std::vector<std::string> names = {"dT", "rate"};
  const Problem problem = quadratic_law(400, 14, 0.05);
  const auto candidates = quadratic_regressors(2);
  const StepwiseFit fit = fit_stepwise(problem.features, problem.target, candidates, names);
  std::vector<Regressor> current;
  const auto rss = [&](const std::vector<Regressor>& regressors) {
    return (problem.target - fit_least_squares(problem.features, problem.target, regressors).predict(problem.features))
        .squaredNorm();
  };
  std::size_t adds = 0;
  for (const auto& step : fit.path) {
    const auto named = std::find_if(candidates.begin(), candidates.end(),
                                    [&](const Regressor& r) { return r.name(names) == step.regressor; });
    ASSERT_NE(named, candidates.end()) << step.regressor;
    if (step.action == "add") {
      std::vector<Regressor> plus = current;
      plus.push_back(*named);
      const double n = 400, p = static_cast<double>(current.size());
      const double f = (rss(current) - rss(plus)) / (rss(plus) / (n - p - 2));
      EXPECT_NEAR(step.f_statistic, f, 1e-6 * f) << step.regressor;
      current = plus;
      ++adds;
    } else {
      std::erase_if(current, [&](const Regressor& r) { return r.name(names) == step.regressor; });
    }
  }
  EXPECT_GE(adds, 2u);
}

// Two candidates that span the same columns with the current fit give the same F to
// rounding: the earlier one enters, and the other adds nothing after it.
TEST(FitStepwise, ATieGoesToTheEarlierCandidate) {
  Random random(5);
  const Eigen::Index n = 300;
  Eigen::MatrixXd features(n, 3);
  Eigen::VectorXd target(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = random.normal(), z = random.normal();
    features(i, 0) = z;
    features(i, 1) = 3.0 * x;   // one direction, twice, in other units
    features(i, 2) = -0.5 * x;
    target(i) = 2.0 * x + 0.3 * z + 0.01 * random.normal();
  }
  const std::vector<std::string> names = {"z", "x", "same_x"};
  const StepwiseFit fit = fit_stepwise(features, target, linear_regressors(3), names);
  std::vector<std::string> added;
  for (const auto& step : fit.path) added.push_back(step.action + " " + step.regressor);
  EXPECT_EQ(added, (std::vector<std::string>{"add x", "add z"}));
}

TEST(FitStepwise, PureNoiseSelectsNothingStrong) {
  Random random(21);
  const Eigen::Index n = 300;
  Eigen::MatrixXd features(n, 2);
  Eigen::VectorXd target(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    features(i, 0) = random.uniform();
    features(i, 1) = random.uniform();
    target(i) = 5.0 + 0.01 * random.normal();
  }
  const StepwiseFit fit = fit_stepwise(features, target, quadratic_regressors(2), {"dT", "rate"});
  EXPECT_LE(fit.model.regressors.size(), 1u);
  EXPECT_NEAR(fit.model.predict(std::vector<double>{0.5, 0.5}), 5.0, 0.01);
}

TEST(FitStepwise, RefusesThresholdsThatCanCycle) {
  const Problem problem = quadratic_law(50, 1, 0.1);
  StepwiseOptions options;
  options.f_to_remove = options.f_to_enter;
  EXPECT_THROW(fit_stepwise(problem.features, problem.target, quadratic_regressors(2), {"dT", "rate"}, options),
               UsageError);
}

TEST(Regressor, NamesParseBack) {
  const std::vector<std::string> names = {"dT", "rate"};
  for (const auto& regressor : quadratic_regressors(2)) {
    EXPECT_EQ(Regressor::parse(regressor.name(names), names).powers, regressor.powers) << regressor.name(names);
  }
  EXPECT_EQ(Regressor::parse("dT^2*rate", names).powers, (std::vector<int>{2, 1}));
  const std::vector<double> at = {3.0, -2.0};
  EXPECT_EQ(Regressor::parse("dT^2*rate", names).evaluate(at), -18.0);
  EXPECT_THROW(Regressor::parse("humidity", names), UsageError);
  EXPECT_THROW(Regressor::parse("dT^x", names), UsageError);
  EXPECT_THROW(Regressor::parse("dT^0", names), UsageError);
}

// Terms that are themselves powers or products: a model whose term is lag:600^2 but not
// lag:600 was written as "lag:600^2" and refused on load ("names unknown term 'lag:600'").
// Such terms are parenthesized inside regressor names and read back to the same powers.
TEST(Regressor, ProductAndPowerTermsParseBack) {
  const std::vector<std::string> names = {"lag:600^2", "dT*rate", "rate", "hinge:420:-3^2*rate"};
  for (const auto& regressor : quadratic_regressors(names.size())) {
    EXPECT_EQ(Regressor::parse(regressor.name(names), names).powers, regressor.powers) << regressor.name(names);
  }
  EXPECT_EQ(linear_regressors(4)[0].name(names), "(lag:600^2)");
  EXPECT_EQ(Regressor::parse("(lag:600^2)^2*(dT*rate)", names).powers, (std::vector<int>{2, 1, 0, 0}));
  // Files written before the parentheses: a whole term still reads as that term.
  EXPECT_EQ(Regressor::parse("lag:600^2", names).powers, (std::vector<int>{1, 0, 0, 0}));
  EXPECT_THROW(Regressor::parse("lag:600^3", names), UsageError);
}

// The batch prediction (evaluate, fit's figures) skips the zero powers the per-sample one
// (the Compensator) multiplies through: the same bits, row by row.
TEST(LinearModel, BatchPredictionIsThePerSampleOneBitForBit) {
  const Problem problem = chamber_like(200, 3);
  Eigen::MatrixXd features(problem.features.rows(), 3);
  features << problem.features, problem.features.col(0).array().cube().matrix();
  const LinearModel model = fit_least_squares(features, problem.target, quadratic_regressors(3));
  const Eigen::VectorXd batch = model.predict(features);
  for (Eigen::Index i = 0; i < features.rows(); ++i) {
    const std::vector<double> row = {features(i, 0), features(i, 1), features(i, 2)};
    ASSERT_EQ(batch(i), model.predict(row)) << "row " << i;
  }
}

TEST(LinearModelJson, RoundTrips) {
  const Problem problem = chamber_like(200, 7);
  const std::vector<std::string> names = {"dT", "rate"};
  const LinearModel model = fit_least_squares(problem.features, problem.target, quadratic_regressors(2));
  const LinearModel back = LinearModel::from_json(nlohmann::json::parse(model.to_json(names).dump()), names);
  EXPECT_EQ(back.intercept, model.intercept);
  EXPECT_EQ(back.coefficients, model.coefficients);
  ASSERT_EQ(back.regressors.size(), model.regressors.size());
  for (std::size_t k = 0; k < back.regressors.size(); ++k) EXPECT_EQ(back.regressors[k].powers, model.regressors[k].powers);
}

TEST(ResidualMetrics, BeforeIsTheVarianceAfterTheMeanSquare) {
  Eigen::VectorXd target(4), prediction(4);
  target << 1, 2, 3, 6;         // mean 3, variance (4+1+0+9)/4
  prediction << 1, 1, 4, 6;     // residual 0, 1, -1, 0
  const ResidualMetrics metrics = residual_metrics(target, prediction);
  EXPECT_EQ(metrics.samples, 4u);
  EXPECT_DOUBLE_EQ(metrics.mse_before, 3.5);
  EXPECT_DOUBLE_EQ(metrics.mse_after, 0.5);
  EXPECT_DOUBLE_EQ(metrics.residual_std, std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(metrics.residual_peak_to_peak, 2.0);
}

// Two independent parts that add up: sd(a) + sd(b) over sd(a + b), √2 for equal spreads.
// Two parts that are nearly the same column with opposite signs: a small difference of
// large terms, the spread of each part over the spread of their difference. A group counts
// as one part, however its columns cancel inside it.
TEST(Cancellation, IsTheSumOfThePartsSpreadsOverTheWholesSpread) {
  Random random(11);
  const Eigen::Index n = 4000;
  Eigen::MatrixXd x(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    x(i, 0) = random.normal();
    x(i, 1) = random.normal();
    x(i, 2) = x(i, 0) + 0.01 * random.normal();
  }
  auto spread = [](const Eigen::VectorXd& v) { return std::sqrt((v.array() - v.mean()).square().mean()); };
  const Eigen::MatrixXd independent = x.leftCols(2);
  EXPECT_NEAR(cancellation(independent, Eigen::Vector2d(1, 1), 0),
              (spread(x.col(0)) + spread(x.col(1))) / spread(x.col(0) + x.col(1)), 1e-12);
  EXPECT_NEAR(cancellation(independent, Eigen::Vector2d(1, 1), 0), std::sqrt(2.0), 0.05);
  EXPECT_DOUBLE_EQ(cancellation(independent, Eigen::Vector2d(3, 0), 0), 1.0) << "one part alone";

  Eigen::MatrixXd near(n, 2);
  near << x.col(0), x.col(2);
  const double expected = (spread(x.col(0)) + spread(x.col(2))) / spread(x.col(2) - x.col(0));
  EXPECT_NEAR(cancellation(near, Eigen::Vector2d(-1, 1), 0), expected, 1e-9 * expected);
  EXPECT_GT(cancellation(near, Eigen::Vector2d(-1, 1), 0), 100.0);
  EXPECT_DOUBLE_EQ(cancellation(near, Eigen::Vector2d(-1, 1), 2), 1.0) << "one group: one part";
  EXPECT_DOUBLE_EQ(cancellation(near, Eigen::Vector2d(0, 0), 0), 1.0) << "a constant fit";
  EXPECT_THROW(cancellation(near, Eigen::Vector3d(1, 1, 1), 0), Error);
}

}  // namespace
}  // namespace thermodrift
