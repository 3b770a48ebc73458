// What every optimizer of optim/ shares: the objective, how a run is controlled
// (threads, seed, budget, progress callback) and what a run returns.
//
// Minimisation throughout: a caller maximising accuracy passes the error instead.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace thermodrift::optim {

// f(x) at a point in the user's coordinates (e.g. (C, σ)). Called concurrently from
// RunControl::threads threads, so it must be thread-safe. NaN counts as +infinity
// (worse than everything); an exception stops the run and is rethrown to the caller.
using Objective = std::function<double(const Eigen::VectorXd&)>;

// What the progress callback sees. Called on the thread that called optimize(), after
// every finished evaluation and after every batch. Mid-batch values (best_value,
// evaluations) depend on which evaluation finished first; the result never does.
struct Progress {
  long iteration = 0;             // optimizer's iteration (AFSA iteration, grid pass, ...)
  long evaluations = 0;           // objective calls so far (cache hits excluded)
  long cache_hits = 0;            // repeated points answered from the cache
  double best_value = 0.0;        // best so far; +infinity before the first evaluation
  double elapsed_seconds = 0.0;
  double fraction_done = 0.0;     // estimate in [0, 1], for progress bars and time left
};

// Returns false to stop the run (Ctrl-C, a time limit, ...): no new evaluation starts
// after that; running ones finish, and the result holds the best point seen.
using ProgressCallback = std::function<bool(const Progress&)>;

struct RunControl {
  int threads = 1;                // threads evaluating the objective; the result does not depend on it
  std::uint64_t seed = 1;         // every random choice derives from it
  long max_evaluations = 0;       // objective calls allowed; 0: only the optimizer's own limits
  bool cache = true;              // answer exactly repeated points from memory instead of re-evaluating
  ProgressCallback callback;      // may be empty

  bool IsValid(std::string* why) const;
};

enum class Termination {
  budget_exhausted,     // the planned work is done: iterations, grid, sample count or max_evaluations
  converged,            // a convergence test fired before the budget ran out
  stopped_by_callback,  // the progress callback returned false
};
const char* to_string(Termination termination);

struct HistoryPoint {
  long evaluations = 0;  // objective calls so far
  double best_value = 0.0;  // best value so far

  friend bool operator==(const HistoryPoint&, const HistoryPoint&) = default;
};

struct OptimizationResult {
  Eigen::VectorXd best_point;       // user coordinates; empty when nothing was evaluated
  double best_value = 0.0;          // +infinity when nothing was evaluated
  long evaluations = 0;             // objective calls (cache hits excluded)
  long cache_hits = 0;              // points answered from the cache
  long iterations = 0;              // iterations (AFSA) / passes (grid) / batches (random) completed
  std::vector<HistoryPoint> history;  // after each batch that evaluated something
  Termination termination = Termination::budget_exhausted;
  double seconds = 0.0;             // wall clock; the only field that depends on the thread count
};

// One line: "best 1.234e-05 at (12.3, 0.45) after 2310 evaluations (41 cached), 0.8 s,
// budget exhausted".
std::string BriefReport(const OptimizationResult& result);

}  // namespace thermodrift::optim
