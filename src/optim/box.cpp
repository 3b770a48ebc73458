#include "thermodrift/optim/box.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "thermodrift/error.hpp"

namespace thermodrift::optim {

Box::Box(Eigen::VectorXd lower_bounds, Eigen::VectorXd upper_bounds)
    : lower(std::move(lower_bounds)), upper(std::move(upper_bounds)) {}

Box::Box(Eigen::VectorXd lower_bounds, Eigen::VectorXd upper_bounds, std::vector<bool> log)
    : lower(std::move(lower_bounds)), upper(std::move(upper_bounds)), log_scale(std::move(log)) {}

bool Box::is_log(Eigen::Index dim) const {
  return !log_scale.empty() && log_scale[static_cast<std::size_t>(dim)];
}

bool Box::IsValid(std::string* why) const {
  const Invalid fail(why);
  if (lower.size() == 0) return fail("box: no dimensions");
  if (upper.size() != lower.size())
    return fail(fmt::format("box: {} lower bounds but {} upper bounds", lower.size(), upper.size()));
  if (!log_scale.empty() && static_cast<Eigen::Index>(log_scale.size()) != lower.size())
    return fail(fmt::format("box: {} log-scale flags for {} dimensions", log_scale.size(),
                            lower.size()));
  for (Eigen::Index d = 0; d < lower.size(); ++d) {
    if (!std::isfinite(lower[d]) || !std::isfinite(upper[d]))
      return fail(fmt::format("box: dimension {} has a non-finite bound", d));
    if (lower[d] > upper[d])
      return fail(fmt::format("box: dimension {} has lower {} > upper {}", d, lower[d], upper[d]));
    if (is_log(d) && lower[d] <= 0.0)
      return fail(fmt::format("box: log-scale dimension {} needs lower > 0, got {}", d, lower[d]));
  }
  return true;
}

void Box::validate() const {
  std::string why;
  if (!IsValid(&why)) throw UsageError(why);
}

Eigen::VectorXd Box::FromUnit(const Eigen::VectorXd& unit) const {
  Eigen::VectorXd point(lower.size());
  for (Eigen::Index d = 0; d < lower.size(); ++d) {
    const double u = std::clamp(unit[d], 0.0, 1.0);
    double x;
    if (lower[d] == upper[d]) {
      x = lower[d];
    } else if (is_log(d)) {
      const double log_lower = std::log10(lower[d]);
      x = std::pow(10.0, log_lower + u * (std::log10(upper[d]) - log_lower));
    } else {
      x = lower[d] + u * (upper[d] - lower[d]);
    }
    // The ends map exactly to the bounds, whatever pow() rounds to.
    if (u == 0.0) x = lower[d];
    if (u == 1.0) x = upper[d];
    point[d] = std::clamp(x, lower[d], upper[d]);
  }
  return point;
}

Eigen::VectorXd Box::ToUnit(const Eigen::VectorXd& point) const {
  Eigen::VectorXd unit(lower.size());
  for (Eigen::Index d = 0; d < lower.size(); ++d) {
    const double x = std::clamp(point[d], lower[d], upper[d]);
    double u;
    if (lower[d] == upper[d]) {
      u = 0.0;
    } else if (is_log(d)) {
      const double log_lower = std::log10(lower[d]);
      u = (std::log10(x) - log_lower) / (std::log10(upper[d]) - log_lower);
    } else {
      u = (x - lower[d]) / (upper[d] - lower[d]);
    }
    unit[d] = std::clamp(u, 0.0, 1.0);
  }
  return unit;
}

bool Box::Contains(const Eigen::VectorXd& point) const {
  if (point.size() != lower.size()) return false;
  for (Eigen::Index d = 0; d < lower.size(); ++d)
    if (!(point[d] >= lower[d] && point[d] <= upper[d])) return false;
  return true;
}

}  // namespace thermodrift::optim
