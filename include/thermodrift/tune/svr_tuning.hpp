// Hyper-parameter tuning of the ε-SVR: joins the solver (models/svr.hpp) and the
// box-constrained optimizers (optim/). The objective of a point (C, σ[, ε]) is the error of
// fits at that point, scored in one of three ways (docs/tuning.md):
//
//   cv      blocked k-fold: fold k is a contiguous block of the time-ordered samples;
//           train on the rest (both sides of the block), MSE on the block; mean over folds.
//   holdout train on the first (1 - f) of the samples, MSE on the last f.
//   train   in-sample MSE of one fit on every sample: the paper's choice, optimistic.
//
// Samples of a time series are never shuffled: neighbours of a 100 s moving average are
// near copies, so a shuffled fold would score interpolation, not prediction.
//
//   SvrTuningOptions options;           // AFSA, blocked 5-fold CV, the default box, 49 evaluations
//   options.threads = 2;
//   SvrTuningResult tuned = tune_svr(scaled_features, scaled_target, options);
//   SvrFit fit = SvrTrainer(tuned.solver).train(scaled_features, scaled_target);
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "thermodrift/models/svr.hpp"
#include "thermodrift/optim/afsa.hpp"
#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift {

enum class TuneObjective { cv, holdout, train };
enum class TuneMethod { afsa, grid, random };

// "cv", "holdout", "train" / "afsa", "grid", "random"; UsageError otherwise.
TuneObjective parse_tune_objective(std::string_view text);
TuneMethod parse_tune_method(std::string_view text);
const char* to_string(TuneObjective objective);
const char* to_string(TuneMethod method);

// Rows [begin, end) of the time-ordered samples.
struct SampleRange {
  Eigen::Index begin = 0;
  Eigen::Index end = 0;
  Eigen::Index size() const { return end - begin; }
};

// How cross-validation cuts the training samples into held-out blocks. time: k contiguous
// blocks in time (blocked_folds). runs: with two or more runs (separate chamber logs), one
// block per run, each predicted by the fit on the others (leave-one-run-out): the test of
// a model on a run it has not seen; with one run, as time.
enum class FoldsBy { time, runs };
FoldsBy parse_folds_by(std::string_view text);  // "time", "runs"; UsageError otherwise
const char* to_string(FoldsBy folds_by);

struct SvrTuningOptions {
  TuneMethod method = TuneMethod::afsa;
  TuneObjective objective = TuneObjective::cv;
  int folds = 5;                    // cv: contiguous blocks in time (at least 2)
  // cv: these held-out blocks instead of `folds` blocked folds (one per run for
  // leave-one-run-out, from cv_blocks); sorted, disjoint, each non-empty.
  std::vector<SampleRange> blocks;
  double holdout_fraction = 0.3;    // holdout: the last part of the time-ordered samples, in (0, 1)

  // The box, in standardized units, every dimension log-scaled. The default is the issue's
  // 7 x 7 grid box: C in [0.1, 1e4], γ in [1e-3, 100] ⇔ σ = 1/√(2γ) in [0.0707, 22.36].
  double C_min = 0.1, C_max = 1e4;
  double sigma_min = 0.070710678118654752, sigma_max = 22.360679774997897;
  bool tune_epsilon = false;        // search ε too (third dimension); else ε = `epsilon`
  double epsilon = 0.01;            // fixed ε when !tune_epsilon (standardized target units)
  double epsilon_min = 1e-3, epsilon_max = 0.5;  // ε range when tune_epsilon

  // Budget of objective evaluations (each is `folds` fits for cv, one otherwise).
  // grid: the smallest p^d grid holding it, cut in grid.py's coarse-first order;
  // random: that many points; afsa: fish and iterations sized to it (afsa_for_budget),
  // with the budget as a hard cap.
  long evaluations = 49;            // the 7 x 7 budget, measured in docs/tuning.md
  int threads = 1;                  // evaluations in parallel; the result does not depend on it
  std::uint64_t seed = 1;           // AFSA's and random search's streams

  // Solver settings of the final fit (the caller's refit with SvrTuningResult::solver).
  // C, gamma and epsilon are ignored: the search sets them. threads is forced to 1 inside
  // the search when threads > 1 (the parallelism is across evaluations).
  SvrOptions solver;
  // During the search only: a looser tolerance and a cap on SMO steps, because the slow
  // corners of the box (large C, small σ) would otherwise dominate the run (docs/tuning.md).
  // 0 means: as in `solver`.
  double search_tolerance = 1e-2;
  long search_max_iterations = 20'000;
  // Squared distances of each training subset kept in memory when the samples have more
  // than kDistanceFeatures features and all subsets fit this budget together (then a
  // kernel column is n exp()s, not n distances over every feature); 0: always computed
  // from the samples per column. With the paper's pair or a few terms a distance costs
  // less than reading it from memory (docs/svr.md); with the tens of terms of
  // `--features auto` the stored distances cut the tuning's CPU time by more than half
  // (docs/tuning.md).
  static constexpr Eigen::Index kDistanceFeatures = 16;
  double distance_budget_mb = 256;

  optim::ProgressCallback progress;  // forwarded to the optimizer; returning false stops

  bool IsValid(std::string* why) const;
};

struct SvrTuningResult {
  double C = 0, sigma = 0, gamma = 0, epsilon = 0;  // the bulletin board; gamma = 1/(2σ²)
  // Objective at that point, as an MSE in the standardized target units of the input
  // (multiply by target_scale² for (°/h)²), computed with the search's solver settings.
  double objective_value = 0;
  TuneObjective objective = TuneObjective::cv;
  bool optimistic = false;          // objective == train: in-sample, not a prediction error
  long evaluations = 0;             // objective evaluations (cache hits excluded)
  long fits = 0;                    // SVR fits run (evaluations × folds for cv)
  long capped_fits = 0;             // fits stopped at search_max_iterations (still scored)
  long low_rank_fits = 0;           // fits solved through a complete low-rank factor (SvrApproximation::low_rank)
  std::vector<optim::HistoryPoint> history;
  optim::Termination termination = optim::Termination::budget_exhausted;
  double seconds = 0;               // wall clock of the search
  SvrOptions solver;                // options.solver with the tuned C, gamma, epsilon: refit with it

  std::string BriefReport() const;  // one line, "optimistic" spelled out for train
};

// The k contiguous blocks of blocked k-fold CV over n samples: block i is
// [⌊i n / k⌋, ⌊(i+1) n / k⌋), so they cover 0..n-1 once, in order, sizes differing by ≤ 1.
// UsageError unless 2 ≤ k ≤ n.
std::vector<SampleRange> blocked_folds(Eigen::Index samples, int folds);
// The held-out blocks of cross-validation over `samples` rows whose runs start at
// `run_start` (FeatureTable::run_start): one block per non-empty run when `by` is runs and
// there are two or more of them (`by` stays runs), else blocked_folds(samples, folds) (`by`
// is time).
struct HeldOutBlocks {
  std::vector<SampleRange> blocks;
  FoldsBy by = FoldsBy::time;
  std::string describe() const;  // "blocked 10-fold" or "leave-one-run-out (3 runs)"
};
HeldOutBlocks cv_blocks(Eigen::Index samples, const std::vector<std::size_t>& run_start, int folds, FoldsBy by);
// The rows outside `block`, in order: a fold's training rows.
Eigen::MatrixXd rows_except(const Eigen::MatrixXd& matrix, SampleRange block);
Eigen::VectorXd rows_except(const Eigen::VectorXd& vector, SampleRange block);
// The held-out part of a holdout split: the last round(f n) samples (at least one, and at
// least one left to train on). UsageError unless n ≥ 2 and 0 < f < 1.
SampleRange holdout_range(Eigen::Index samples, double fraction);

// AFSA options whose expected evaluations fit `budget` in `dimensions` dimensions:
// the project's AFSA defaults with fewer fish and iterations (docs/tuning.md).
optim::Afsa::Options afsa_for_budget(long budget, int dimensions);

// The objective of a point (C, σ[, ε]), without an optimizer: the cv/holdout/train MSE.
// Same value tune_svr would see. Exposed for tests and for reporting a chosen point.
class SvrObjective {
 public:
  // samples/targets: standardized, time-ordered rows of ONE axis. Builds the training
  // subsets' SvrDatasets once. Throws UsageError for bad sizes or options.
  SvrObjective(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets,
               const SvrTuningOptions& options);
  ~SvrObjective();
  SvrObjective(const SvrObjective&) = delete;
  SvrObjective& operator=(const SvrObjective&) = delete;

  // MSE at (C, σ, ε) with the search's solver settings. Thread-safe.
  double operator()(double C, double sigma, double epsilon) const;
  long fits() const;         // fits run so far
  long capped_fits() const;  // of those, stopped at the iteration cap
  long low_rank_fits() const;  // of those, solved through a complete low-rank factor
  // Whether the training subsets keep their squared distances (options.distance_budget_mb).
  bool stores_distances() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Tunes (C, σ[, ε]) on standardized, time-ordered rows of ONE axis. Throws UsageError for
// invalid options or data (fewer samples than folds + 1, say).
SvrTuningResult tune_svr(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets,
                         const SvrTuningOptions& options);

}  // namespace thermodrift
