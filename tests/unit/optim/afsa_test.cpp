#include "thermodrift/optim/afsa.hpp"

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "thermodrift/error.hpp"
#include "thermodrift/optim/test_problems.hpp"

namespace thermodrift::optim {
namespace {

// Tolerances are set from measured runs with the default options (worst of seeds 1-10,
// docs/optim.md), with margin; the budget is the default run (~4,600 evaluations).
struct Case {
  TestProblem (*make)(int);
  int dim;
  double tolerance;  // on best_value - minimum
};

class AfsaFindsMinimum : public testing::TestWithParam<Case> {};

TEST_P(AfsaFindsMinimum, WithinToleranceAndBudget) {
  const Case& c = GetParam();
  const TestProblem problem = c.make(c.dim);
  const Afsa afsa;
  for (std::uint64_t seed : {1, 2, 3}) {
    RunControl control;
    control.seed = seed;
    const OptimizationResult result = afsa.optimize(problem.objective, problem.box, control);
    EXPECT_LT(result.best_value - problem.minimum, c.tolerance) << problem.name << " seed " << seed;
    EXPECT_LE(result.evaluations, 6000) << problem.name;
    EXPECT_EQ(result.termination, Termination::budget_exhausted);
    EXPECT_EQ(result.iterations, afsa.options().iterations);
    EXPECT_DOUBLE_EQ(problem.objective(result.best_point), result.best_value);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Problems, AfsaFindsMinimum,
    testing::Values(Case{RosenbrockProblem, 2, 1e-2}, Case{RosenbrockProblem, 5, 10.0},
                    Case{RastriginProblem, 2, 1.5},  // 0.995: the ring of local minima next to 0
                    Case{RastriginProblem, 5, 20.0},  // random search: ~25 at this budget
                    Case{AckleyProblem, 2, 0.05}, Case{AckleyProblem, 5, 3.0},
                    Case{ShiftedSphereProblem, 2, 1e-5}, Case{ShiftedSphereProblem, 5, 1e-3},
                    Case{LogShiftedSphereProblem, 2, 1e-5}, Case{LogShiftedSphereProblem, 5, 1e-3}));

TEST(Afsa, BeatsRandomSearchOnTheRoughFunctions) {
  // Not a proof, a regression guard: the swarm must do better than its own initial scatter.
  const TestProblem problem = AckleyProblem(5);
  const OptimizationResult result = Afsa().optimize(problem.objective, problem.box, {});
  ASSERT_GE(result.history.size(), 2u);
  EXPECT_LT(result.history.back().best_value, 0.1 * result.history.front().best_value);
}

TEST(Afsa, ScheduleShrinksFromInitialToFloor) {
  Afsa::Options options;
  options.iterations = 11;
  for (auto schedule : {Afsa::Schedule::linear, Afsa::Schedule::exponential}) {
    options.schedule = schedule;
    const Afsa afsa(options);
    EXPECT_DOUBLE_EQ(afsa.visual_range_at(0), options.visual_range);
    EXPECT_NEAR(afsa.visual_range_at(10), options.visual_range_floor, 1e-15);
    EXPECT_NEAR(afsa.step_at(10), options.step_floor, 1e-15);
    for (int t = 1; t <= 10; ++t) EXPECT_LT(afsa.step_at(t), afsa.step_at(t - 1));
  }
  options.schedule = Afsa::Schedule::constant;
  EXPECT_DOUBLE_EQ(Afsa(options).step_at(10), options.step);
}

TEST(Afsa, ConstantScheduleIsTheSeedsAlgorithmAndStillImproves) {
  Afsa::Options options;
  options.schedule = Afsa::Schedule::constant;
  const TestProblem problem = ShiftedSphereProblem(2);
  const OptimizationResult result = Afsa(options).optimize(problem.objective, problem.box, {});
  EXPECT_LT(result.best_value, 1e-2);
}

TEST(Afsa, StallTestEndsTheRunAsConverged) {
  Afsa::Options options;
  options.iterations = 500;
  options.stall_iterations = 5;
  options.stall_tolerance = 1e-9;
  const TestProblem problem = ShiftedSphereProblem(2);
  const OptimizationResult result = Afsa(options).optimize(problem.objective, problem.box, {});
  EXPECT_EQ(result.termination, Termination::converged);
  EXPECT_LT(result.iterations, 500);
}

TEST(Afsa, EvaluationBudgetIsHonouredExactly) {
  const TestProblem problem = RastriginProblem(2);
  RunControl control;
  control.max_evaluations = 777;
  const OptimizationResult result = Afsa().optimize(problem.objective, problem.box, control);
  EXPECT_EQ(result.evaluations, 777);
  EXPECT_EQ(result.termination, Termination::budget_exhausted);
  EXPECT_LT(result.iterations, Afsa().options().iterations);
}

TEST(Afsa, NanCountsAsWorstAndExceptionsReachTheCaller) {
  const Box box(Eigen::Vector2d(-1.0, -1.0), Eigen::Vector2d(1.0, 1.0));
  auto nan_left = [](const Eigen::VectorXd& x) {
    return x[0] < 0.0 ? std::numeric_limits<double>::quiet_NaN() : x.squaredNorm();
  };
  const OptimizationResult result = Afsa().optimize(nan_left, box, {});
  EXPECT_GE(result.best_point[0], 0.0);
  EXPECT_TRUE(std::isfinite(result.best_value));

  std::atomic<int> calls{0};
  auto failing = [&calls](const Eigen::VectorXd& x) {
    if (++calls == 50) throw std::runtime_error("solver diverged");
    return x.squaredNorm();
  };
  for (int threads : {1, 2}) {
    calls = 0;
    RunControl control;
    control.threads = threads;
    EXPECT_THROW(Afsa().optimize(failing, box, control), std::runtime_error);
  }
}

TEST(AfsaOptions, IsValidRejectsBadSettings) {
  auto rejected = [](auto change) {
    Afsa::Options options;
    change(options);
    std::string why;
    const bool valid = options.IsValid(&why);
    EXPECT_FALSE(why.empty() && !valid);
    return !valid;
  };
  EXPECT_FALSE(rejected([](Afsa::Options&) {}));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.fish = 0; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.iterations = -1; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.crowding_factor = 0.0; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.crowding_factor = 1.0; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.crowding_factor = 1.5; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.crowding_factor = std::nan(""); }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.visual_range = 0.0; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.step = -0.1; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.try_limit = 0; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.visual_range_floor = 0.9; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.step_floor = 0.0; }));
  EXPECT_TRUE(rejected([](Afsa::Options& o) { o.stall_iterations = -2; }));
  EXPECT_FALSE(rejected([](Afsa::Options& o) {
    o.schedule = Afsa::Schedule::constant;
    o.step_floor = 0.0;  // unused without a schedule
  }));
  Afsa::Options bad;
  bad.fish = 0;
  EXPECT_THROW(Afsa{bad}, UsageError);
}

}  // namespace
}  // namespace thermodrift::optim
