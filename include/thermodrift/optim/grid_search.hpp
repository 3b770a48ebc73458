// Grid search in the style of libsvm's grid.py: an evenly spaced grid in the unit cube
// (so a log grid on log-scale dimensions), evaluated coarse points first, with optional
// coarse-to-fine refinement around the best point.
#pragma once

#include <string>
#include <vector>

#include "thermodrift/optim/box.hpp"
#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift::optim {

class GridSearch {
 public:
  struct Options {
    int points_per_dimension = 7;  // grid points along each side (7 x 7 is libsvm's habit); 1: the centre
    int refinements = 0;           // extra passes, each a grid of the same size spanning one
                                   //   spacing either side of the best point so far
    long max_points = 10'000'000;  // refuse grids larger than this (points_per_dimension^dim)

    bool IsValid(std::string* why) const;
  };

  GridSearch() = default;
  explicit GridSearch(Options options);  // throws UsageError when !options.IsValid

  const Options& options() const { return options_; }

  // Evaluates the grid (then the refinements), one batch per "ring" of grid.py's order,
  // so a budget smaller than the grid still covers the whole box coarsely. The seed is
  // unused: grid search is deterministic.
  OptimizationResult optimize(const Objective& objective, const Box& box,
                              const RunControl& control = {}) const;

  // grid.py's order of indices 0..count-1: the middle first, then the middles of the
  // halves, alternating left and right. Exposed for the tests.
  static std::vector<int> CoarseFirstOrder(int count);

 private:
  Options options_;
};

}  // namespace thermodrift::optim
