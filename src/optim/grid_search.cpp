#include "thermodrift/optim/grid_search.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/error.hpp"
#include "thermodrift/optim/batch_evaluator.hpp"

namespace thermodrift::optim {

namespace {

// Grid coordinates along one dimension of one pass, indexed 0..count-1.
using Axis = std::vector<double>;

// The first pass: k / (count - 1), exactly 0 and 1 at the ends.
Axis FullAxis(int count) {
  Axis axis(static_cast<std::size_t>(count), 0.5);
  if (count > 1)
    for (int k = 0; k < count; ++k) axis[static_cast<std::size_t>(k)] = static_cast<double>(k) / (count - 1);
  return axis;
}

// A refinement: centre ± spacing, written as centre + spacing (2k - (count-1))/(count-1)
// so the middle point is the centre exactly (then the cache answers it) and points past
// the cube's faces clamp onto them (and repeat, and the cache answers those too).
Axis RefinedAxis(int count, double centre, double spacing) {
  Axis axis(static_cast<std::size_t>(count), centre);
  if (count > 1)
    for (int k = 0; k < count; ++k)
      axis[static_cast<std::size_t>(k)] = std::clamp(
          centre + spacing * static_cast<double>(2 * k - (count - 1)) / (count - 1), 0.0, 1.0);
  return axis;
}

// One pass over the grid axes[0] x axes[1] x ..., batch by batch: batch L holds the points
// whose largest per-dimension rank in the coarse-first order is L, so the grid fills in
// from coarse to fine as grid.py's does. Returns false when the evaluator says stop.
bool EvaluateGrid(const std::vector<Axis>& axes, const std::vector<int>& order, BatchEvaluator& evaluator) {
  const auto dim = static_cast<Eigen::Index>(axes.size());
  const int count = static_cast<int>(order.size());
  std::vector<std::vector<Eigen::VectorXd>> levels(static_cast<std::size_t>(count));
  std::vector<int> rank(static_cast<std::size_t>(dim), 0);  // odometer over ranks
  while (true) {
    Eigen::VectorXd point(dim);
    int level = 0;
    for (Eigen::Index d = 0; d < dim; ++d) {
      const int r = rank[static_cast<std::size_t>(d)];
      point[d] = axes[static_cast<std::size_t>(d)][static_cast<std::size_t>(order[static_cast<std::size_t>(r)])];
      level = std::max(level, r);
    }
    levels[static_cast<std::size_t>(level)].push_back(std::move(point));
    Eigen::Index d = dim - 1;
    while (d >= 0 && ++rank[static_cast<std::size_t>(d)] == count) rank[static_cast<std::size_t>(d--)] = 0;
    if (d < 0) break;
  }
  for (const auto& level : levels) {
    evaluator.evaluate(level);
    if (evaluator.should_stop()) return false;
  }
  return true;
}

}  // namespace

bool GridSearch::Options::IsValid(std::string* why) const {
  const Invalid fail(why, "grid search");
  if (points_per_dimension < 1)
    return fail(fmt::format("points_per_dimension must be >= 1, got {}", points_per_dimension));
  if (refinements < 0) return fail(fmt::format("refinements must be >= 0, got {}", refinements));
  if (max_points < 1) return fail(fmt::format("max_points must be >= 1, got {}", max_points));
  return true;
}

GridSearch::GridSearch(Options options) : options_(std::move(options)) {
  std::string why;
  if (!options_.IsValid(&why)) throw UsageError(why);
}

std::vector<int> GridSearch::CoarseFirstOrder(int count) {
  std::vector<int> indices(static_cast<std::size_t>(std::max(count, 0)));
  for (int k = 0; k < count; ++k) indices[static_cast<std::size_t>(k)] = k;
  // grid.py's permute_sequence, recursively on [first, last).
  auto permute = [](auto&& self, const std::vector<int>& sequence) -> std::vector<int> {
    if (sequence.size() <= 1) return sequence;
    const std::size_t middle = sequence.size() / 2;
    std::deque<int> left, right;
    for (int k : self(self, std::vector<int>(sequence.begin(), sequence.begin() + static_cast<long>(middle))))
      left.push_back(k);
    for (int k : self(self, std::vector<int>(sequence.begin() + static_cast<long>(middle) + 1, sequence.end())))
      right.push_back(k);
    std::vector<int> result{sequence[middle]};
    while (!left.empty() || !right.empty()) {
      if (!left.empty()) result.push_back(left.front()), left.pop_front();
      if (!right.empty()) result.push_back(right.front()), right.pop_front();
    }
    return result;
  };
  return permute(permute, indices);
}

OptimizationResult GridSearch::optimize(const Objective& objective, const Box& box,
                                        const RunControl& control) const {
  box.validate();
  const int count = options_.points_per_dimension;
  const auto dim = box.dimension();
  double grid_points = std::pow(static_cast<double>(count), static_cast<double>(dim));
  if (grid_points > static_cast<double>(options_.max_points))
    throw UsageError(fmt::format("grid search: {}^{} = {:.3g} points exceed max_points = {}", count, dim,
                                 grid_points, options_.max_points));
  BatchEvaluator evaluator(objective, box, control);
  const std::vector<int> order = CoarseFirstOrder(count);

  std::vector<Axis> axes(static_cast<std::size_t>(dim), FullAxis(count));
  std::vector<double> spacing(static_cast<std::size_t>(dim), count > 1 ? 1.0 / (count - 1) : 0.0);
  const int passes = 1 + options_.refinements;
  long completed = 0;
  for (int pass = 0; pass < passes; ++pass) {
    evaluator.set_iteration(pass, static_cast<double>(pass) / passes);
    if (pass > 0) {
      const Eigen::VectorXd& centre = evaluator.best_unit_point();
      if (centre.size() != dim) break;  // nothing finite to refine around
      for (Eigen::Index d = 0; d < dim; ++d) {
        const auto k = static_cast<std::size_t>(d);
        axes[k] = RefinedAxis(count, centre[d], spacing[k]);
        spacing[k] = count > 1 ? 2.0 * spacing[k] / (count - 1) : 0.0;
      }
    }
    if (!EvaluateGrid(axes, order, evaluator)) break;
    completed = pass + 1;
  }
  return evaluator.Result(Termination::budget_exhausted, completed);
}

}  // namespace thermodrift::optim
