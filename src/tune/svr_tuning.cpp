// Tuning of the ε-SVR's (C, σ[, ε]) by the optimizers of optim/ (docs/tuning.md).
//
// Cost model: an evaluation is `folds` fits (cv) or one (holdout, train). The training
// subsets do not depend on the point, so their SvrDatasets are built once, before the
// optimizer runs, and shared read-only by every evaluation on every thread. Each fit is a
// pure function of (subset, C, γ, ε) — no warm start from "the previous evaluation",
// which would depend on the order threads finish in — so the optimizer's determinism
// across thread counts carries over to the tuned result.
#include "thermodrift/tune/svr_tuning.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "thermodrift/error.hpp"
#include "thermodrift/optim/box.hpp"
#include "thermodrift/optim/grid_search.hpp"
#include "thermodrift/optim/random_search.hpp"

namespace thermodrift {

TuneObjective parse_tune_objective(std::string_view text) {
  if (text == "cv") return TuneObjective::cv;
  if (text == "holdout") return TuneObjective::holdout;
  if (text == "train") return TuneObjective::train;
  throw UsageError(fmt::format("unknown tuning objective '{}' (expected cv, holdout or train)", text));
}

TuneMethod parse_tune_method(std::string_view text) {
  if (text == "afsa") return TuneMethod::afsa;
  if (text == "grid") return TuneMethod::grid;
  if (text == "random") return TuneMethod::random;
  throw UsageError(fmt::format("unknown tuning method '{}' (expected afsa, grid or random)", text));
}

const char* to_string(TuneObjective objective) {
  switch (objective) {
    case TuneObjective::cv: return "cv";
    case TuneObjective::holdout: return "holdout";
    case TuneObjective::train: return "train";
  }
  return "?";
}

const char* to_string(TuneMethod method) {
  switch (method) {
    case TuneMethod::afsa: return "afsa";
    case TuneMethod::grid: return "grid";
    case TuneMethod::random: return "random";
  }
  return "?";
}

FoldsBy parse_folds_by(std::string_view text) {
  if (text == "time") return FoldsBy::time;
  if (text == "runs") return FoldsBy::runs;
  throw UsageError(fmt::format("unknown folds '{}' (expected time or runs)", text));
}

const char* to_string(FoldsBy folds_by) { return folds_by == FoldsBy::runs ? "runs" : "time"; }

namespace {

bool fail(std::string* why, std::string reason) {
  if (why) *why = std::move(reason);
  return false;
}

bool valid_range(double low, double high) {
  return std::isfinite(low) && std::isfinite(high) && low > 0 && low <= high;
}

}  // namespace

bool SvrTuningOptions::IsValid(std::string* why) const {
  if (folds < 2) return fail(why, fmt::format("folds must be at least 2 (got {})", folds));
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    if (blocks[k].begin < (k ? blocks[k - 1].end : 0) || blocks[k].size() < 1) {
      return fail(why, fmt::format("held-out block {} [{}, {}) is empty or overlaps the one before", k,
                                   blocks[k].begin, blocks[k].end));
    }
  }
  if (blocks.size() == 1) return fail(why, "one held-out block leaves nothing to compare: give two or more");
  if (!(holdout_fraction > 0 && holdout_fraction < 1)) {
    return fail(why, fmt::format("holdout_fraction must be in (0, 1) (got {:g})", holdout_fraction));
  }
  if (!valid_range(C_min, C_max)) return fail(why, fmt::format("need 0 < C_min <= C_max (got {:g}, {:g})", C_min, C_max));
  if (!valid_range(sigma_min, sigma_max)) {
    return fail(why, fmt::format("need 0 < sigma_min <= sigma_max (got {:g}, {:g})", sigma_min, sigma_max));
  }
  if (tune_epsilon && !valid_range(epsilon_min, epsilon_max)) {
    return fail(why, fmt::format("need 0 < epsilon_min <= epsilon_max (got {:g}, {:g})", epsilon_min, epsilon_max));
  }
  if (!tune_epsilon && !(std::isfinite(epsilon) && epsilon >= 0)) {
    return fail(why, fmt::format("epsilon must be finite and >= 0 (got {:g})", epsilon));
  }
  if (evaluations < 1) return fail(why, fmt::format("evaluations must be at least 1 (got {})", evaluations));
  if (threads < 1) return fail(why, fmt::format("threads must be at least 1 (got {})", threads));
  if (!(search_tolerance >= 0 && std::isfinite(search_tolerance))) {
    return fail(why, fmt::format("search_tolerance must be >= 0 (got {:g})", search_tolerance));
  }
  if (search_max_iterations < 0) {
    return fail(why, fmt::format("search_max_iterations must be >= 0 (got {})", search_max_iterations));
  }
  if (!(distance_budget_mb >= 0)) return fail(why, "distance_budget_mb must be >= 0");
  std::string solver_why;
  if (!solver.IsValid(&solver_why)) return fail(why, "solver: " + solver_why);
  return true;
}

std::string SvrTuningResult::BriefReport() const {
  return fmt::format("{} MSE {:.4g}{} at C = {:.4g}, sigma = {:.4g} (gamma = {:.4g}), epsilon = {:.4g}; "
                     "{} evaluations, {} fits ({} at the iteration cap), {:.1f} s, {}",
                     to_string(objective), objective_value, optimistic ? " (in-sample, optimistic)" : "", C,
                     sigma, gamma, epsilon, evaluations, fits, capped_fits, seconds,
                     optim::to_string(termination));
}

std::vector<SampleRange> blocked_folds(Eigen::Index samples, int folds) {
  if (folds < 2 || samples < folds) {
    throw UsageError(fmt::format("blocked {}-fold cross-validation needs at least {} samples (got {})", folds,
                                 std::max(folds, 2), samples));
  }
  std::vector<SampleRange> blocks;
  for (int k = 0; k < folds; ++k) {
    blocks.push_back({samples * k / folds, samples * (k + 1) / folds});
  }
  return blocks;
}

std::string HeldOutBlocks::describe() const {
  return by == FoldsBy::runs ? fmt::format("leave-one-run-out ({} runs)", blocks.size())
                             : fmt::format("blocked {}-fold", blocks.size());
}

HeldOutBlocks cv_blocks(Eigen::Index samples, const std::vector<std::size_t>& run_start, int folds, FoldsBy by) {
  std::vector<SampleRange> runs;
  if (by == FoldsBy::runs) {
    for (std::size_t k = 0; k < run_start.size(); ++k) {
      const auto begin = static_cast<Eigen::Index>(run_start[k]);
      const auto end = k + 1 < run_start.size() ? static_cast<Eigen::Index>(run_start[k + 1]) : samples;
      if (end > begin) runs.push_back({begin, end});
    }
  }
  if (runs.size() >= 2) return {std::move(runs), FoldsBy::runs};
  return {blocked_folds(samples, folds), FoldsBy::time};
}

SampleRange holdout_range(Eigen::Index samples, double fraction) {
  if (samples < 2 || !(fraction > 0 && fraction < 1)) {
    throw UsageError(fmt::format("a holdout split needs at least 2 samples and a fraction in (0, 1) "
                                 "(got {} samples, {:g})", samples, fraction));
  }
  const auto held = std::clamp<Eigen::Index>(
      static_cast<Eigen::Index>(std::llround(fraction * static_cast<double>(samples))), 1, samples - 1);
  return {samples - held, samples};
}

optim::Afsa::Options afsa_for_budget(long budget, int dimensions) {
  // Measured on optim's test problems (2-D and 3-D, 4-10 fish, 2-10 iterations): a run
  // costs about fish + 3 · fish · iterations evaluations (one swarm centre, about one
  // prey probe, one or two candidates per fish and iteration). √(budget/3) fish balances
  // scatter against refinement; the budget stays a hard cap on top.
  optim::Afsa::Options options;
  const double per_fish_iteration = 3.0;
  const double fish = std::clamp(std::round(std::sqrt(static_cast<double>(budget) / per_fish_iteration)),
                                 static_cast<double>(std::max(4, dimensions + 2)), 20.0);
  options.fish = static_cast<int>(fish);
  // Rounded rather than floored, so the budget is spent, not left over: when the run
  // overshoots, the cap cuts the last iteration in batch order (deterministically).
  options.iterations = std::max(
      1, static_cast<int>(std::lround((static_cast<double>(budget) - fish) / (per_fish_iteration * fish))));
  // With a handful of iterations the default floors (r 0.002, λ 0.001) would be reached in
  // three or four halvings; on a (C, σ) surface a hundredth of the box (0.05-0.1 decades)
  // is as fine as the CV error can tell apart.
  options.visual_range_floor = 0.05;
  options.step_floor = 0.01;
  return options;
}

// ---------------------------------------------------------------------------------------
// The objective.

Eigen::MatrixXd rows_except(const Eigen::MatrixXd& matrix, SampleRange block) {
  Eigen::MatrixXd out(matrix.rows() - block.size(), matrix.cols());
  out.topRows(block.begin) = matrix.topRows(block.begin);
  out.bottomRows(matrix.rows() - block.end) = matrix.bottomRows(matrix.rows() - block.end);
  return out;
}

Eigen::VectorXd rows_except(const Eigen::VectorXd& vector, SampleRange block) {
  Eigen::VectorXd out(vector.size() - block.size());
  out.head(block.begin) = vector.head(block.begin);
  out.tail(vector.size() - block.end) = vector.tail(vector.size() - block.end);
  return out;
}

struct SvrObjective::State {
  // One fit and what it is scored on.
  struct Split {
    SvrDataset training;
    Eigen::VectorXd training_targets;
    Eigen::MatrixXd scoring_samples;  // empty: score on the training samples (train objective)
    Eigen::VectorXd scoring_targets;
  };
  std::vector<Split> splits;
  SvrOptions search;  // solver settings of every search fit; C, gamma, epsilon set per point
  mutable std::atomic<long> fits{0};
  mutable std::atomic<long> capped_fits{0};
  mutable std::atomic<long> low_rank_fits{0};
};

SvrObjective::SvrObjective(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets,
                           const SvrTuningOptions& options)
    : state_(std::make_unique<State>()) {
  std::string why;
  if (!options.IsValid(&why)) throw UsageError("SVR tuning options: " + why);
  if (samples.rows() != targets.size()) {
    throw UsageError(fmt::format("SVR tuning: {} samples but {} targets", samples.rows(), targets.size()));
  }
  if (samples.rows() < 3 || samples.cols() < 1) {
    throw UsageError(fmt::format("SVR tuning needs at least 3 samples and 1 feature (got {} x {})",
                                 samples.rows(), samples.cols()));
  }
  if (!samples.allFinite() || !targets.allFinite()) throw UsageError("SVR tuning: samples or targets not finite");

  const Eigen::Index n = samples.rows();
  std::vector<SampleRange> held_out;  // empty range: the train objective
  switch (options.objective) {
    case TuneObjective::cv:
      if (!options.blocks.empty()) {
        if (options.blocks.back().end > n) {
          throw UsageError(fmt::format("held-out blocks reach sample {} of {}", options.blocks.back().end, n));
        }
        held_out = options.blocks;
        break;
      }
      if (n < 2 * options.folds) {
        throw UsageError(fmt::format("blocked {}-fold CV needs at least {} samples (got {})", options.folds,
                                     2 * options.folds, n));
      }
      held_out = blocked_folds(n, options.folds);
      break;
    case TuneObjective::holdout: held_out.push_back(holdout_range(n, options.holdout_fraction)); break;
    case TuneObjective::train: held_out.push_back({n, n}); break;
  }
  // Squared distances only with many features, and when every subset's n² doubles fit
  // the budget together.
  double distance_mb = 0;
  for (const auto& block : held_out) {
    const double m = static_cast<double>(n - block.size());
    distance_mb += m * m * sizeof(double) / (1024.0 * 1024.0);
  }
  const bool store_distances = samples.cols() > SvrTuningOptions::kDistanceFeatures &&
                               distance_mb <= options.distance_budget_mb;
  const double per_subset_budget = store_distances ? 1e300 : 0.0;

  for (const auto& block : held_out) {
    State::Split split{SvrDataset(rows_except(samples, block), per_subset_budget), rows_except(targets, block), {}, {}};
    if (block.size() > 0) {
      split.scoring_samples = samples.middleRows(block.begin, block.size());
      split.scoring_targets = targets.segment(block.begin, block.size());
    }
    state_->splits.push_back(std::move(split));
  }

  state_->search = options.solver;
  if (options.search_tolerance > 0) state_->search.tolerance = options.search_tolerance;
  if (options.search_max_iterations > 0) state_->search.max_iterations = options.search_max_iterations;
  if (options.threads > 1) state_->search.threads = 1;
}

SvrObjective::~SvrObjective() = default;

double SvrObjective::operator()(double C, double sigma, double epsilon) const {
  SvrOptions settings = state_->search;
  settings.C = C;
  settings.gamma = gamma_of_sigma(sigma);
  settings.epsilon = epsilon;
  const SvrTrainer trainer(settings);
  // Mean of the per-fold MSEs (each fold's error counts equally, as in k-fold CV).
  double total = 0;
  for (const auto& split : state_->splits) {
    const SvrFit fit = trainer.train(split.training, split.training_targets);
    state_->fits.fetch_add(1, std::memory_order_relaxed);
    if (fit.summary.termination == SvrTermination::iteration_limit) {
      state_->capped_fits.fetch_add(1, std::memory_order_relaxed);
    }
    if (fit.summary.approximation == SvrApproximation::low_rank) {
      state_->low_rank_fits.fetch_add(1, std::memory_order_relaxed);
    }
    const bool in_sample = split.scoring_samples.rows() == 0;
    const Eigen::MatrixXd& scored = in_sample ? split.training.samples() : split.scoring_samples;
    const Eigen::VectorXd& truth = in_sample ? split.training_targets : split.scoring_targets;
    total += (fit.function.predict(scored) - truth).squaredNorm() / static_cast<double>(truth.size());
  }
  return total / static_cast<double>(state_->splits.size());
}

long SvrObjective::fits() const { return state_->fits.load(); }
long SvrObjective::capped_fits() const { return state_->capped_fits.load(); }
long SvrObjective::low_rank_fits() const { return state_->low_rank_fits.load(); }

bool SvrObjective::stores_distances() const {
  return !state_->splits.empty() && state_->splits.front().training.has_distances();
}

// ---------------------------------------------------------------------------------------
// The search.

namespace {

optim::Box tuning_box(const SvrTuningOptions& options) {
  const int dims = options.tune_epsilon ? 3 : 2;
  Eigen::VectorXd lower(dims), upper(dims);
  lower.head(2) << options.C_min, options.sigma_min;
  upper.head(2) << options.C_max, options.sigma_max;
  if (options.tune_epsilon) {
    lower(2) = options.epsilon_min;
    upper(2) = options.epsilon_max;
  }
  return optim::Box(lower, upper, std::vector<bool>(static_cast<std::size_t>(dims), true));
}

// Smallest p with p^dims >= budget.
int grid_side(long budget, int dims) {
  int side = 1;
  while (std::pow(static_cast<double>(side), dims) < static_cast<double>(budget)) ++side;
  return side;
}

}  // namespace

SvrTuningResult tune_svr(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets,
                         const SvrTuningOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const SvrObjective scorer(samples, targets, options);  // validates options and data
  const optim::Box box = tuning_box(options);
  const optim::Objective objective = [&](const Eigen::VectorXd& point) {
    return scorer(point(0), point(1), options.tune_epsilon ? point(2) : options.epsilon);
  };
  optim::RunControl control;
  control.threads = options.threads;
  control.seed = options.seed;
  control.max_evaluations = options.evaluations;
  control.callback = options.progress;

  const int dims = static_cast<int>(box.dimension());
  optim::OptimizationResult run;
  switch (options.method) {
    case TuneMethod::afsa: run = optim::Afsa(afsa_for_budget(options.evaluations, dims)).optimize(objective, box, control); break;
    case TuneMethod::grid: {
      optim::GridSearch::Options grid;
      grid.points_per_dimension = grid_side(options.evaluations, dims);
      run = optim::GridSearch(grid).optimize(objective, box, control);
      break;
    }
    case TuneMethod::random: {
      optim::RandomSearch::Options random;
      random.samples = options.evaluations;
      run = optim::RandomSearch(random).optimize(objective, box, control);
      break;
    }
  }
  if (run.best_point.size() == 0) throw UsageError("SVR tuning stopped before any evaluation");

  SvrTuningResult result;
  result.C = run.best_point(0);
  result.sigma = run.best_point(1);
  result.gamma = gamma_of_sigma(result.sigma);
  result.epsilon = options.tune_epsilon ? run.best_point(2) : options.epsilon;
  result.objective_value = run.best_value;
  result.objective = options.objective;
  result.optimistic = options.objective == TuneObjective::train;
  result.evaluations = run.evaluations;
  result.fits = scorer.fits();
  result.capped_fits = scorer.capped_fits();
  result.low_rank_fits = scorer.low_rank_fits();
  result.history = std::move(run.history);
  result.termination = run.termination;
  result.solver = options.solver;
  result.solver.C = result.C;
  result.solver.gamma = result.gamma;
  result.solver.epsilon = result.epsilon;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace thermodrift
