#include "thermodrift/optim/random_search.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/error.hpp"
#include "thermodrift/optim/batch_evaluator.hpp"
#include "thermodrift/optim/random_stream.hpp"

namespace thermodrift::optim {

bool RandomSearch::Options::IsValid(std::string* why) const {
  const Invalid fail(why, "random search");
  if (samples < 1) return fail(fmt::format("samples must be >= 1, got {}", samples));
  if (batch_size < 1) return fail(fmt::format("batch_size must be >= 1, got {}", batch_size));
  return true;
}

RandomSearch::RandomSearch(Options options) : options_(std::move(options)) {
  std::string why;
  if (!options_.IsValid(&why)) throw UsageError(why);
}

OptimizationResult RandomSearch::optimize(const Objective& objective, const Box& box,
                                          const RunControl& control) const {
  BatchEvaluator evaluator(objective, box, control);
  long drawn = 0;
  long batches = 0;
  while (drawn < options_.samples && !evaluator.should_stop()) {
    const long size = std::min<long>(options_.batch_size, options_.samples - drawn);
    std::vector<Eigen::VectorXd> batch;
    batch.reserve(static_cast<std::size_t>(size));
    for (long k = drawn; k < drawn + size; ++k)
      batch.push_back(RandomStream(control.seed, 0, static_cast<std::uint64_t>(k))
                          .unit_cube_point(box.dimension()));
    evaluator.set_iteration(batches, static_cast<double>(drawn) / static_cast<double>(options_.samples));
    evaluator.evaluate(batch);
    drawn += size;
    if (!evaluator.should_stop()) ++batches;
  }
  return evaluator.Result(Termination::budget_exhausted, batches);
}

}  // namespace thermodrift::optim
