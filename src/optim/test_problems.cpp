#include "thermodrift/optim/test_problems.hpp"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "thermodrift/error.hpp"

namespace thermodrift::optim {

namespace {

void CheckDimension(int dim, int at_least, const char* name) {
  if (dim < at_least) throw UsageError(fmt::format("{} needs dimension >= {}, got {}", name, at_least, dim));
}

Eigen::VectorXd Shift(int dim) {
  Eigen::VectorXd shift(dim);
  for (int k = 0; k < dim; ++k) shift[k] = 1.234 - 0.71 * k;
  return shift;
}

Box Cube(int dim, double half_width) {
  return Box(Eigen::VectorXd::Constant(dim, -half_width), Eigen::VectorXd::Constant(dim, half_width));
}

}  // namespace

double rosenbrock(const Eigen::VectorXd& x) {
  double sum = 0.0;
  for (Eigen::Index k = 0; k + 1 < x.size(); ++k) {
    const double valley = x[k + 1] - x[k] * x[k];
    sum += 100.0 * valley * valley + (1.0 - x[k]) * (1.0 - x[k]);
  }
  return sum;
}

double rastrigin(const Eigen::VectorXd& x) {
  double sum = 10.0 * static_cast<double>(x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k)
    sum += x[k] * x[k] - 10.0 * std::cos(2.0 * std::numbers::pi * x[k]);
  return sum;
}

double ackley(const Eigen::VectorXd& x) {
  const double n = static_cast<double>(x.size());
  double cosines = 0.0;
  for (Eigen::Index k = 0; k < x.size(); ++k) cosines += std::cos(2.0 * std::numbers::pi * x[k]);
  return -20.0 * std::exp(-0.2 * std::sqrt(x.squaredNorm() / n)) - std::exp(cosines / n) + 20.0 +
         std::numbers::e;
}

double shifted_sphere(const Eigen::VectorXd& x, const Eigen::VectorXd& shift) {
  return (x - shift).squaredNorm();
}

TestProblem RosenbrockProblem(int dim) {
  CheckDimension(dim, 2, "rosenbrock");
  return {fmt::format("rosenbrock-{}d", dim), rosenbrock,
          Box(Eigen::VectorXd::Constant(dim, -5.0), Eigen::VectorXd::Constant(dim, 10.0)),
          Eigen::VectorXd::Ones(dim), 0.0};
}

TestProblem RastriginProblem(int dim) {
  CheckDimension(dim, 1, "rastrigin");
  return {fmt::format("rastrigin-{}d", dim), rastrigin, Cube(dim, 5.12), Eigen::VectorXd::Zero(dim), 0.0};
}

TestProblem AckleyProblem(int dim) {
  CheckDimension(dim, 1, "ackley");
  return {fmt::format("ackley-{}d", dim), ackley, Cube(dim, 32.768), Eigen::VectorXd::Zero(dim), 0.0};
}

TestProblem ShiftedSphereProblem(int dim) {
  CheckDimension(dim, 1, "shifted sphere");
  const Eigen::VectorXd shift = Shift(dim);
  return {fmt::format("shifted-sphere-{}d", dim),
          [shift](const Eigen::VectorXd& x) { return shifted_sphere(x, shift); }, Cube(dim, 5.0), shift,
          0.0};
}

TestProblem LogShiftedSphereProblem(int dim) {
  CheckDimension(dim, 1, "log shifted sphere");
  const Eigen::VectorXd shift = Shift(dim);
  Eigen::VectorXd minimiser(dim);
  for (int k = 0; k < dim; ++k) minimiser[k] = std::pow(10.0, shift[k]);
  return {fmt::format("log-shifted-sphere-{}d", dim),
          [shift](const Eigen::VectorXd& x) {
            return shifted_sphere(x.array().log10().matrix(), shift);
          },
          Box(Eigen::VectorXd::Constant(dim, 1e-3), Eigen::VectorXd::Constant(dim, 1e4),
              std::vector<bool>(static_cast<std::size_t>(dim), true)),
          minimiser, 0.0};
}

}  // namespace thermodrift::optim
