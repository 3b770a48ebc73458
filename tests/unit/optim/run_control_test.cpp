// What every optimizer owes its caller: thread-count independence, the cache, prompt
// stops, bounds, budgets. Checked on all three optimizers.
#include <algorithm>
#include <atomic>
#include <functional>
#include <mutex>

#include <gtest/gtest.h>

#include "thermodrift/error.hpp"
#include "thermodrift/optim/afsa.hpp"
#include "thermodrift/optim/grid_search.hpp"
#include "thermodrift/optim/random_search.hpp"
#include "thermodrift/optim/test_problems.hpp"

namespace thermodrift::optim {
namespace {

using Run = std::function<OptimizationResult(const Objective&, const Box&, const RunControl&)>;

struct Named {
  const char* name;
  Run run;
};

std::vector<Named> Optimizers() {
  Afsa::Options afsa;
  afsa.iterations = 20;
  GridSearch::Options grid;
  grid.points_per_dimension = 9;
  grid.refinements = 3;
  RandomSearch::Options random;
  random.samples = 300;
  return {
      {"afsa", [afsa](const Objective& f, const Box& b, const RunControl& c) { return Afsa(afsa).optimize(f, b, c); }},
      {"grid", [grid](const Objective& f, const Box& b, const RunControl& c) { return GridSearch(grid).optimize(f, b, c); }},
      {"random", [random](const Objective& f, const Box& b, const RunControl& c) {
         return RandomSearch(random).optimize(f, b, c);
       }},
  };
}

// A (C, σ)-like log box with a linear third dimension, and a rough function on it.
Box MixedBox() { return Box(Eigen::Vector3d(0.1, 1e-3, -2.0), Eigen::Vector3d(1e4, 100.0, 2.0), {true, true, false}); }
double Rough(const Eigen::VectorXd& x) {
  Eigen::VectorXd y(3);
  y << std::log10(x[0]) - 1.3, std::log10(x[1]) + 0.4, x[2] - 0.3;
  return rastrigin(y);
}

TEST(RunControl, ResultIsIdenticalForOneAndTwoThreads) {
  for (const auto& optimizer : Optimizers()) {
    RunControl one;
    one.seed = 42;
    RunControl two = one;
    two.threads = 2;
    const OptimizationResult a = optimizer.run(Rough, MixedBox(), one);
    const OptimizationResult b = optimizer.run(Rough, MixedBox(), two);
    EXPECT_EQ(a.best_point, b.best_point) << optimizer.name;  // bitwise
    EXPECT_EQ(a.best_value, b.best_value) << optimizer.name;
    EXPECT_EQ(a.history, b.history) << optimizer.name;
    EXPECT_EQ(a.evaluations, b.evaluations) << optimizer.name;
    EXPECT_EQ(a.cache_hits, b.cache_hits) << optimizer.name;
    EXPECT_EQ(a.iterations, b.iterations) << optimizer.name;
  }
}

TEST(RunControl, DifferentSeedsGiveDifferentRuns) {
  RunControl one, other;
  other.seed = 2;
  EXPECT_NE(Afsa().optimize(Rough, MixedBox(), one).best_point,
            Afsa().optimize(Rough, MixedBox(), other).best_point);
}

TEST(RunControl, CacheMeansObjectiveCallsEqualReportedEvaluations) {
  for (const auto& optimizer : Optimizers()) {
    for (bool cache : {true, false}) {
      std::atomic<long> calls{0};
      // The minimum is on a corner, so clamped moves repeat points exactly.
      auto corner = [&calls](const Eigen::VectorXd& x) {
        ++calls;
        return -x.sum();
      };
      RunControl control;
      control.threads = 2;
      control.cache = cache;
      const OptimizationResult result = optimizer.run(corner, MixedBox(), control);
      EXPECT_EQ(calls.load(), result.evaluations) << optimizer.name;
      if (!cache) EXPECT_EQ(result.cache_hits, 0) << optimizer.name;
      if (cache && std::string(optimizer.name) != "random") EXPECT_GT(result.cache_hits, 0) << optimizer.name;
    }
  }
}

TEST(RunControl, CallbackStopHaltsAtOnce) {
  for (const auto& optimizer : Optimizers()) {
    for (int threads : {1, 2}) {
      std::atomic<long> calls{0};
      auto counted = [&calls](const Eigen::VectorXd& x) {
        ++calls;
        return Rough(x);
      };
      long seen_at_stop = -1;
      RunControl control;
      control.threads = threads;
      control.callback = [&seen_at_stop](const Progress& progress) {
        EXPECT_GE(progress.fraction_done, 0.0);
        EXPECT_LE(progress.fraction_done, 1.0);
        if (progress.evaluations >= 37) {
          if (seen_at_stop < 0) seen_at_stop = progress.evaluations;
          return false;
        }
        return true;
      };
      const OptimizationResult result = optimizer.run(counted, MixedBox(), control);
      EXPECT_EQ(result.termination, Termination::stopped_by_callback) << optimizer.name;
      // The callback hears of every evaluation before its worker takes another point;
      // after "stop" only those already running (at most threads - 1 others) may finish.
      EXPECT_LE(calls.load(), seen_at_stop + threads - 1) << optimizer.name << " threads " << threads;
      EXPECT_EQ(calls.load(), result.evaluations) << optimizer.name;
      EXPECT_TRUE(MixedBox().Contains(result.best_point)) << optimizer.name;
    }
  }
}

TEST(RunControl, EveryEvaluatedPointIsInsideTheBox) {
  for (const auto& optimizer : Optimizers()) {
    std::mutex mutex;
    long outside = 0, total = 0;
    auto recording = [&](const Eigen::VectorXd& x) {
      std::lock_guard lock(mutex);
      ++total;
      if (!MixedBox().Contains(x)) ++outside;
      return -x[0] + x[1] * x[2];  // drives the search into faces and corners
    };
    RunControl control;
    control.threads = 2;
    optimizer.run(recording, MixedBox(), control);
    EXPECT_GT(total, 0);
    EXPECT_EQ(outside, 0) << optimizer.name;
  }
}

TEST(RunControl, BudgetCapsEveryOptimizer) {
  for (const auto& optimizer : Optimizers()) {
    RunControl control;
    control.max_evaluations = 25;
    const OptimizationResult result = optimizer.run(Rough, MixedBox(), control);
    EXPECT_EQ(result.evaluations, 25) << optimizer.name;
    EXPECT_EQ(result.termination, Termination::budget_exhausted) << optimizer.name;
    EXPECT_EQ(result.history.back().evaluations, 25) << optimizer.name;
  }
}

TEST(RunControl, HistoryIsMonotoneAndEndsAtTheResult) {
  for (const auto& optimizer : Optimizers()) {
    const OptimizationResult result = optimizer.run(Rough, MixedBox(), {});
    ASSERT_FALSE(result.history.empty()) << optimizer.name;
    for (std::size_t k = 1; k < result.history.size(); ++k) {
      EXPECT_GT(result.history[k].evaluations, result.history[k - 1].evaluations);
      EXPECT_LE(result.history[k].best_value, result.history[k - 1].best_value);
    }
    EXPECT_EQ(result.history.back().evaluations, result.evaluations);
    EXPECT_EQ(result.history.back().best_value, result.best_value);
    EXPECT_FALSE(BriefReport(result).empty());
  }
}

TEST(RunControl, InvalidSettingsAreUsageErrors) {
  RunControl control;
  control.threads = 0;
  std::string why;
  EXPECT_FALSE(control.IsValid(&why));
  EXPECT_THROW(Afsa().optimize(Rough, MixedBox(), control), UsageError);
  control = {};
  control.max_evaluations = -1;
  EXPECT_THROW(RandomSearch().optimize(Rough, MixedBox(), control), UsageError);
  EXPECT_THROW(GridSearch().optimize(Rough, Box(), {}), UsageError);
  EXPECT_THROW(Afsa().optimize(Objective{}, MixedBox(), {}), UsageError);
}

}  // namespace
}  // namespace thermodrift::optim
