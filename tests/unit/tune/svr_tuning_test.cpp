// Tests of tune/svr_tuning: the splits, the objectives, the search's determinism across
// threads and its quality against a fine grid on a small problem.
#include "thermodrift/tune/svr_tuning.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

struct Problem {
  Eigen::MatrixXd samples;
  Eigen::VectorXd targets;
};

// y = sin(3x) + noise on x uniform in [-1, 1], standardized. Rows in drawing order, so
// every blocked fold covers the whole range of x (`sorted`: rows in x order, so the
// edge folds extrapolate, as a held-out cycle may).
Problem sine_problem(int count, double noise_std, unsigned seed, bool sorted = false) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_std);
  std::vector<double> x(static_cast<std::size_t>(count));
  for (double& value : x) value = uniform(generator);
  if (sorted) std::sort(x.begin(), x.end());
  Problem problem{Eigen::MatrixXd(count, 1), Eigen::VectorXd(count)};
  for (int i = 0; i < count; ++i) {
    problem.samples(i, 0) = x[static_cast<std::size_t>(i)] / 0.577;  // ≈ unit std
    problem.targets(i) = std::sin(3 * x[static_cast<std::size_t>(i)]) + noise(generator);
  }
  const double mean = problem.targets.mean();
  const double std = std::sqrt((problem.targets.array() - mean).square().mean());
  problem.targets = (problem.targets.array() - mean) / std;
  return problem;
}

TEST(BlockedFolds, ContiguousInOrderAndCoverEverySampleOnce) {
  for (Eigen::Index n : {10, 11, 17, 300, 2271}) {
    for (int k : {2, 3, 5, 7, 10}) {
      const auto folds = blocked_folds(n, k);
      ASSERT_EQ(folds.size(), static_cast<std::size_t>(k));
      std::vector<int> seen(static_cast<std::size_t>(n), 0);
      Eigen::Index expected_begin = 0;
      for (const auto& fold : folds) {
        EXPECT_EQ(fold.begin, expected_begin) << "n " << n << " k " << k;  // contiguous, in time order
        EXPECT_GT(fold.size(), 0);
        EXPECT_LE(std::abs(fold.size() - n / k), 1);  // balanced
        for (Eigen::Index i = fold.begin; i < fold.end; ++i) ++seen[static_cast<std::size_t>(i)];
        expected_begin = fold.end;
      }
      EXPECT_EQ(expected_begin, n);
      EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
    }
  }
}

TEST(BlockedFolds, RejectsTooFewSamplesOrFolds) {
  EXPECT_THROW(blocked_folds(10, 1), UsageError);
  EXPECT_THROW(blocked_folds(3, 5), UsageError);
}

TEST(CvBlocks, OneBlockPerRunWhenThereAreTwoOrMore) {
  // Runs start at rows 0, 30, 30 (an empty run: left out) and 70 of 100.
  const HeldOutBlocks runs = cv_blocks(100, {0, 30, 30, 70}, 5, FoldsBy::runs);
  EXPECT_EQ(runs.by, FoldsBy::runs);
  ASSERT_EQ(runs.blocks.size(), 3u);
  EXPECT_EQ(runs.blocks[0].begin, 0);
  EXPECT_EQ(runs.blocks[0].end, 30);
  EXPECT_EQ(runs.blocks[1].begin, 30);
  EXPECT_EQ(runs.blocks[1].end, 70);
  EXPECT_EQ(runs.blocks[2].begin, 70);
  EXPECT_EQ(runs.blocks[2].end, 100);
  EXPECT_EQ(runs.describe(), "leave-one-run-out (3 runs)");
  // One run, or folds in time asked for: blocked folds.
  for (const HeldOutBlocks& time : {cv_blocks(100, {0}, 5, FoldsBy::runs), cv_blocks(100, {0, 30, 30, 70}, 5, FoldsBy::time)}) {
    EXPECT_EQ(time.by, FoldsBy::time);
    ASSERT_EQ(time.blocks.size(), 5u);
    EXPECT_EQ(time.blocks[1].begin, 20);
    EXPECT_EQ(time.describe(), "blocked 5-fold");
  }
  EXPECT_EQ(parse_folds_by(to_string(FoldsBy::runs)), FoldsBy::runs);
  EXPECT_EQ(parse_folds_by(to_string(FoldsBy::time)), FoldsBy::time);
  EXPECT_THROW(parse_folds_by("shuffled"), UsageError);
}

TEST(CvBlocks, ExplicitBlocksScoreAsTheSameBlockedFolds) {
  // Two explicit halves are blocked 2-fold CV: the same objective, to the bit.
  const Problem problem = sine_problem(60, 0.1, 3);
  SvrTuningOptions folds;
  folds.folds = 2;
  SvrTuningOptions halves;
  halves.blocks = {{0, 30}, {30, 60}};
  const SvrObjective by_folds(problem.samples, problem.targets, folds);
  const SvrObjective by_blocks(problem.samples, problem.targets, halves);
  EXPECT_EQ(by_folds(10, 0.5, 0.01), by_blocks(10, 0.5, 0.01));
  // Uneven runs are not halves: another objective.
  halves.blocks = {{0, 10}, {10, 60}};
  EXPECT_NE(SvrObjective(problem.samples, problem.targets, halves)(10, 0.5, 0.01), by_folds(10, 0.5, 0.01));
  // Blocks must be two or more, non-empty, in order and inside the samples.
  for (const std::vector<SampleRange>& bad : std::vector<std::vector<SampleRange>>{
           {{0, 60}}, {{0, 30}, {30, 30}}, {{0, 40}, {30, 60}}}) {
    SvrTuningOptions options;
    options.blocks = bad;
    EXPECT_FALSE(options.IsValid(nullptr));
  }
  halves.blocks = {{0, 30}, {30, 61}};
  EXPECT_THROW(tune_svr(problem.samples, problem.targets, halves), UsageError);
}

TEST(HoldoutRange, TakesTheLastPart) {
  const SampleRange held = holdout_range(100, 0.3);
  EXPECT_EQ(held.begin, 70);
  EXPECT_EQ(held.end, 100);
  const SampleRange tiny = holdout_range(10, 0.01);  // at least one held out
  EXPECT_EQ(tiny.begin, 9);
  EXPECT_EQ(tiny.end, 10);
  const SampleRange most = holdout_range(10, 0.99);  // at least one to train on
  EXPECT_EQ(most.begin, 1);
  EXPECT_THROW(holdout_range(100, 0.0), UsageError);
  EXPECT_THROW(holdout_range(100, 1.0), UsageError);
  EXPECT_THROW(holdout_range(1, 0.5), UsageError);
}

TEST(SvrObjective, HoldoutScoresTheLastPartOnly) {
  // Targets 0 everywhere except the last 30 %: a model trained on the first 70 % predicts
  // ≈ 0, so the holdout MSE is ≈ the mean square of the last part's targets (4).
  Problem problem = sine_problem(100, 0.0, 3, true);
  problem.targets.setZero();
  problem.targets.tail(30).setConstant(2.0);
  SvrTuningOptions options;
  options.objective = TuneObjective::holdout;
  options.holdout_fraction = 0.3;
  const SvrObjective objective(problem.samples, problem.targets, options);
  EXPECT_NEAR(objective(1.0, 1.0, 0.01), 4.0, 0.05);
  EXPECT_EQ(objective.fits(), 1);
}

TEST(SvrObjective, TrainIsOptimisticAgainstCv) {
  const Problem problem = sine_problem(300, 0.3, 5);
  for (TuneObjective kind : {TuneObjective::train, TuneObjective::cv}) {
    SvrTuningOptions options;
    options.objective = kind;
    const SvrObjective objective(problem.samples, problem.targets, options);
    EXPECT_EQ(objective.fits(), 0);
  }
  SvrTuningOptions options;
  options.objective = TuneObjective::train;
  const SvrObjective train(problem.samples, problem.targets, options);
  options.objective = TuneObjective::cv;
  const SvrObjective cv(problem.samples, problem.targets, options);
  // A flexible point (large C, narrow kernel) fits the noise: in-sample error far below CV.
  const double in_sample = train(1000.0, 0.1, 0.01);
  const double cross_validated = cv(1000.0, 0.1, 0.01);
  EXPECT_LT(in_sample, cross_validated);
  EXPECT_EQ(cv.fits(), 5);
  EXPECT_EQ(train.fits(), 1);
}

TEST(SvrObjective, CappedFitsStillScore) {
  const Problem problem = sine_problem(200, 0.3, 7);
  SvrTuningOptions options;
  options.objective = TuneObjective::holdout;
  options.search_max_iterations = 5;
  const SvrObjective objective(problem.samples, problem.targets, options);
  const double value = objective(1e4, 0.07, 0.01);
  EXPECT_TRUE(std::isfinite(value));
  EXPECT_EQ(objective.capped_fits(), 1);
}

// The identified terms of `--features auto` are tens of columns: the tuning then keeps
// each training subset's squared distances, and every score is the one computed from the
// samples (the same sums in the same order).
TEST(SvrObjective, StoredDistancesScoreAsComputedOnes) {
  const Problem base = sine_problem(400, 0.2, 17);
  const Eigen::Index wide = SvrTuningOptions::kDistanceFeatures + 4;
  std::mt19937 generator(5);
  std::normal_distribution<double> jitter(0.0, 0.3);
  Eigen::MatrixXd samples(base.samples.rows(), wide);
  for (Eigen::Index row = 0; row < samples.rows(); ++row) {
    for (Eigen::Index column = 0; column < wide; ++column) {
      samples(row, column) = base.samples(row, 0) * std::cos(0.3 * static_cast<double>(column)) + jitter(generator);
    }
  }
  SvrTuningOptions options;
  const SvrObjective stored(samples, base.targets, options);
  ASSERT_TRUE(stored.stores_distances());
  options.distance_budget_mb = 0;
  const SvrObjective computed(samples, base.targets, options);
  ASSERT_FALSE(computed.stores_distances());
  for (const auto& [C, sigma] : {std::pair{0.5, 0.3}, std::pair{10.0, 2.0}, std::pair{1e3, 6.0}}) {
    const double from_memory = stored(C, sigma, 0.01);
    const double from_samples = computed(C, sigma, 0.01);
    EXPECT_NEAR(from_memory, from_samples, 1e-12 * from_samples) << "C " << C << " sigma " << sigma;
  }
  EXPECT_EQ(stored.capped_fits(), computed.capped_fits());
  // Few features: a distance is cheaper to compute than to read, so none is kept.
  EXPECT_FALSE(SvrObjective(base.samples, base.targets, SvrTuningOptions{}).stores_distances());
  // Over the budget: none either.
  SvrTuningOptions tight;
  tight.distance_budget_mb = 0.5;
  EXPECT_FALSE(SvrObjective(samples, base.targets, tight).stores_distances());
}

// Also the sanitize pass's check of the threaded tuning, so it is kept small: 106 s there
// at 300 samples and 30 evaluations.
TEST(SvrTuning, IdenticalForOneAndTwoThreads) {
  const Problem problem = sine_problem(150, 0.2, 11);
  for (TuneMethod method : {TuneMethod::afsa, TuneMethod::random}) {
    SvrTuningOptions options;
    options.method = method;
    options.evaluations = 16;
    options.seed = 42;
    options.threads = 1;
    const SvrTuningResult one = tune_svr(problem.samples, problem.targets, options);
    options.threads = 2;
    const SvrTuningResult two = tune_svr(problem.samples, problem.targets, options);
    EXPECT_EQ(one.C, two.C) << to_string(method);  // bitwise
    EXPECT_EQ(one.sigma, two.sigma);
    EXPECT_EQ(one.objective_value, two.objective_value);
    EXPECT_EQ(one.evaluations, two.evaluations);
    EXPECT_EQ(one.fits, two.fits);
    EXPECT_EQ(one.history, two.history);
  }
}

TEST(SvrTuning, AfsaIsNearTheBestOfAFineGrid) {
  const Problem problem = sine_problem(200, 0.2, 13);
  SvrTuningOptions options;
  options.threads = 2;
  const SvrObjective cv(problem.samples, problem.targets, options);
  // A fine 13 x 13 log grid over the default box (0.42 decades in C, 0.21 in σ).
  double best = std::numeric_limits<double>::infinity(), worst = 0;
  for (int i = 0; i < 13; ++i) {
    for (int j = 0; j < 13; ++j) {
      const double C = options.C_min * std::pow(options.C_max / options.C_min, i / 12.0);
      const double sigma = options.sigma_min * std::pow(options.sigma_max / options.sigma_min, j / 12.0);
      const double value = cv(C, sigma, options.epsilon);
      best = std::min(best, value);
      worst = std::max(worst, value);
    }
  }
  options.evaluations = 60;
  const SvrTuningResult tuned = tune_svr(problem.samples, problem.targets, options);
  EXPECT_LE(tuned.objective_value, worst);
  EXPECT_LE(tuned.objective_value, best * 1.05) << "fine grid best " << best << ", AFSA " << tuned.BriefReport();
  EXPECT_LE(tuned.evaluations, 60);
  // The reported value is the objective at the reported point.
  EXPECT_DOUBLE_EQ(cv(tuned.C, tuned.sigma, tuned.epsilon), tuned.objective_value);
  EXPECT_DOUBLE_EQ(tuned.gamma, 1 / (2 * tuned.sigma * tuned.sigma));
  EXPECT_EQ(tuned.solver.C, tuned.C);
  EXPECT_EQ(tuned.solver.gamma, tuned.gamma);
  EXPECT_FALSE(tuned.optimistic);
}

TEST(SvrTuning, GridUsesTheBudgetAndTrainIsLabelledOptimistic) {
  const Problem problem = sine_problem(120, 0.2, 17);
  SvrTuningOptions options;
  options.method = TuneMethod::grid;
  options.objective = TuneObjective::train;
  options.evaluations = 9;  // a 3 x 3 grid
  const SvrTuningResult tuned = tune_svr(problem.samples, problem.targets, options);
  EXPECT_EQ(tuned.evaluations, 9);
  EXPECT_EQ(tuned.fits, 9);
  EXPECT_TRUE(tuned.optimistic);
  EXPECT_NE(tuned.BriefReport().find("optimistic"), std::string::npos);
}

TEST(SvrTuning, TunesEpsilonWhenAsked) {
  const Problem problem = sine_problem(120, 0.2, 19);
  SvrTuningOptions options;
  options.tune_epsilon = true;
  options.objective = TuneObjective::holdout;
  options.evaluations = 20;
  const SvrTuningResult tuned = tune_svr(problem.samples, problem.targets, options);
  EXPECT_GE(tuned.epsilon, options.epsilon_min);
  EXPECT_LE(tuned.epsilon, options.epsilon_max);
  EXPECT_NE(tuned.epsilon, options.epsilon);
}

TEST(SvrTuning, ProgressCallbackStops) {
  const Problem problem = sine_problem(120, 0.2, 23);
  SvrTuningOptions options;
  options.objective = TuneObjective::holdout;
  options.evaluations = 50;
  int calls = 0;
  options.progress = [&](const optim::Progress&) { return ++calls < 3; };
  const SvrTuningResult tuned = tune_svr(problem.samples, problem.targets, options);
  EXPECT_EQ(tuned.termination, optim::Termination::stopped_by_callback);
  EXPECT_LT(tuned.evaluations, 50);
}

TEST(SvrTuningOptions, Validation) {
  std::string why;
  EXPECT_TRUE(SvrTuningOptions{}.IsValid(&why)) << why;
  auto invalid = [](auto change) {
    SvrTuningOptions options;
    change(options);
    std::string reason;
    const bool ok = options.IsValid(&reason);
    return !ok && !reason.empty();
  };
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.folds = 1; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.holdout_fraction = 0; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.holdout_fraction = 1; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.C_min = 0; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.C_max = 0.01; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.sigma_min = -1; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.sigma_max = std::numeric_limits<double>::infinity(); }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.tune_epsilon = true; o.epsilon_min = 0; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.epsilon = -0.1; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.evaluations = 0; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.threads = 0; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.search_max_iterations = -1; }));
  EXPECT_TRUE(invalid([](SvrTuningOptions& o) { o.solver.tolerance = 0; }));

  const Problem problem = sine_problem(20, 0.1, 1);
  SvrTuningOptions bad;
  bad.folds = 1;
  EXPECT_THROW(tune_svr(problem.samples, problem.targets, bad), UsageError);
  SvrTuningOptions too_many_folds;
  too_many_folds.folds = 15;  // 20 samples cannot make 15 folds of at least 2
  EXPECT_THROW(tune_svr(problem.samples, problem.targets, too_many_folds), UsageError);
  EXPECT_THROW(tune_svr(problem.samples, problem.targets.head(10), SvrTuningOptions{}), UsageError);
}

TEST(TuneEnums, ParseAndPrint) {
  for (TuneObjective o : {TuneObjective::cv, TuneObjective::holdout, TuneObjective::train}) {
    EXPECT_EQ(parse_tune_objective(to_string(o)), o);
  }
  for (TuneMethod m : {TuneMethod::afsa, TuneMethod::grid, TuneMethod::random}) {
    EXPECT_EQ(parse_tune_method(to_string(m)), m);
  }
  EXPECT_THROW(parse_tune_objective("kfold"), UsageError);
  EXPECT_THROW(parse_tune_method("pso"), UsageError);
}

TEST(AfsaForBudget, FitsTheBudget) {
  for (long budget : {20L, 49L, 100L, 300L}) {
    const auto options = afsa_for_budget(budget, 2);
    std::string why;
    EXPECT_TRUE(options.IsValid(&why)) << why;
    // fish + ≈3 evaluations per fish and iteration (docs/tuning.md)
    EXPECT_LE(options.fish + 3L * options.fish * options.iterations, budget + 3L * options.fish);
  }
}

}  // namespace
}  // namespace thermodrift
