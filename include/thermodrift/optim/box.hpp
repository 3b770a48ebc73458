// The search box of a box-constrained minimisation, and the map between the user's
// coordinates (C, σ, ...) and the unit cube in which every optimizer works.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace thermodrift::optim {

// Per dimension: lower <= x <= upper. A log-scale dimension (lower > 0) is searched
// uniformly in log10(x), which is how SVM hyper-parameters are searched: C = 1 and C = 10
// are as far apart as C = 1000 and C = 10000.
//
// Unit-cube coordinate u in [0, 1]:
//   linear: x = lower + u (upper - lower)
//   log:    x = 10^(log10 lower + u (log10 upper - log10 lower))
// A dimension with lower == upper is fixed: every u maps to lower, and lower maps to u = 0.
struct Box {
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;
  std::vector<bool> log_scale;  // empty: every dimension linear

  Box() = default;
  // All dimensions linear.
  Box(Eigen::VectorXd lower, Eigen::VectorXd upper);
  Box(Eigen::VectorXd lower, Eigen::VectorXd upper, std::vector<bool> log_scale);

  Eigen::Index dimension() const { return lower.size(); }
  bool is_log(Eigen::Index dim) const;

  // False (and why, when `why` is not null) unless sizes agree, bounds are finite,
  // lower <= upper, and log dimensions have lower > 0.
  bool IsValid(std::string* why) const;
  // Throws UsageError with the reason when !IsValid.
  void validate() const;

  // Unit cube -> user coordinates. u is clamped to [0, 1] first, and the result to
  // [lower, upper], so rounding in pow() can never leave the box.
  Eigen::VectorXd FromUnit(const Eigen::VectorXd& unit) const;
  // User coordinates -> unit cube (x is clamped to the box first).
  Eigen::VectorXd ToUnit(const Eigen::VectorXd& point) const;
  bool Contains(const Eigen::VectorXd& point) const;
};

}  // namespace thermodrift::optim
