// Evaluates batches of points for an optimizer: on RunControl::threads threads, through
// a cache of points already seen, within the evaluation budget, calling the progress
// callback, and keeping the bulletin board (best point so far) and the history.
//
// Determinism: within a batch, evaluations may finish in any order, but everything that
// feeds back into the search (values, cache, bulletin board, history) is updated after
// the batch, in the order of the points in the batch. So a run's result is the same for
// any thread count; only mid-batch progress reports and `seconds` vary.
#pragma once

#include <chrono>
#include <limits>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "thermodrift/optim/box.hpp"
#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift::optim {

class BatchEvaluator {
 public:
  static constexpr double kNotEvaluated = std::numeric_limits<double>::infinity();

  // Keeps references to all three: they must outlive the evaluator. Throws UsageError
  // when the box or the run control is invalid.
  BatchEvaluator(const Objective& objective, const Box& box, const RunControl& control);

  // f at each point, given in unit-cube coordinates. A point that could not be evaluated
  // (budget exhausted, callback stop) gets kNotEvaluated (+infinity), as does a NaN value.
  // Check should_stop() after every call. Rethrows the first exception of the objective.
  std::vector<double> evaluate(const std::vector<Eigen::VectorXd>& unit_points);
  double evaluate(const Eigen::VectorXd& unit_point);

  // True once the budget is spent or the callback said stop.
  bool should_stop() const { return stopped_by_callback_ || budget_exhausted(); }
  bool budget_exhausted() const {
    return control_.max_evaluations > 0 && evaluations_ >= control_.max_evaluations;
  }
  // Objective calls still allowed (a large number when there is no budget).
  long remaining_evaluations() const;

  // What progress reports say: the optimizer's iteration and its own estimate of the
  // fraction done (the evaluation budget's fraction is used when larger).
  void set_iteration(long iteration, double fraction_done);

  long evaluations() const { return evaluations_; }
  double best_value() const { return best_value_; }
  const Eigen::VectorXd& best_unit_point() const { return best_unit_point_; }

  // The run's result. Termination is stopped_by_callback or budget_exhausted when one of
  // those happened, else `otherwise` (what the optimizer decided).
  OptimizationResult Result(Termination otherwise, long iterations) const;

 private:
  // Calls the callback (if any) and records a stop. `best` and `evaluations` may be
  // provisional mid-batch figures.
  void Report(double best, long evaluations);

  const Objective& objective_;
  const Box& box_;
  const RunControl& control_;
  std::chrono::steady_clock::time_point start_;

  std::map<std::vector<double>, double> cache_;  // user coordinates -> f (exact match)
  long evaluations_ = 0;
  long cache_hits_ = 0;
  long iteration_ = 0;
  double fraction_done_ = 0.0;
  bool stopped_by_callback_ = false;
  double best_value_ = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_point_;       // bulletin board, user coordinates
  Eigen::VectorXd best_unit_point_;  // the same in the unit cube
  std::vector<HistoryPoint> history_;
};

}  // namespace thermodrift::optim
