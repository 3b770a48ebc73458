// Random search: points drawn uniformly in the unit cube, i.e. uniform on linear and
// log-uniform on log-scale dimensions. The baseline every clever optimizer must beat
// at the same budget.
#pragma once

#include <string>

#include "thermodrift/optim/box.hpp"
#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift::optim {

class RandomSearch {
 public:
  struct Options {
    long samples = 100;    // points to evaluate (RunControl::max_evaluations may cut it)
    int batch_size = 32;   // points per batch: one history entry per batch

    bool IsValid(std::string* why) const;
  };

  RandomSearch() = default;
  explicit RandomSearch(Options options);  // throws UsageError when !options.IsValid

  const Options& options() const { return options_; }

  // Sample k is drawn from stream (seed, k) alone, so the points do not depend on the
  // batch size or thread count.
  OptimizationResult optimize(const Objective& objective, const Box& box,
                              const RunControl& control = {}) const;

 private:
  Options options_;
};

}  // namespace thermodrift::optim
