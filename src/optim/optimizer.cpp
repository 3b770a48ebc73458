#include "thermodrift/error.hpp"
#include "thermodrift/optim/optimizer.hpp"

#include <fmt/format.h>

namespace thermodrift::optim {

bool RunControl::IsValid(std::string* why) const {
  const Invalid fail(why);
  if (threads < 1) return fail(fmt::format("threads must be at least 1, got {}", threads));
  if (max_evaluations < 0)
    return fail(fmt::format("max_evaluations must be >= 0 (0: no limit), got {}", max_evaluations));
  return true;
}

const char* to_string(Termination termination) {
  switch (termination) {
    case Termination::budget_exhausted: return "budget exhausted";
    case Termination::converged: return "converged";
    case Termination::stopped_by_callback: return "stopped by callback";
  }
  return "unknown";
}

std::string BriefReport(const OptimizationResult& result) {
  std::string point;
  for (Eigen::Index d = 0; d < result.best_point.size(); ++d)
    point += fmt::format("{}{:.6g}", d == 0 ? "" : ", ", result.best_point[d]);
  return fmt::format("best {:.6g} at ({}) after {} evaluations ({} cached), {:.3g} s, {}",
                     result.best_value, point, result.evaluations, result.cache_hits,
                     result.seconds, to_string(result.termination));
}

}  // namespace thermodrift::optim
