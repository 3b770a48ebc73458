// Standard test functions of global optimisation, as library code (as ensmallen ships
// them) so tests, benchmarks and examples share one definition. Each comes with its
// usual search box and its known minimum.
#pragma once

#include <string>

#include <Eigen/Core>

#include "thermodrift/optim/box.hpp"
#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift::optim {

struct TestProblem {
  std::string name;             // e.g. "rosenbrock-2d"
  Objective objective;          // thread-safe (pure functions)
  Box box;
  Eigen::VectorXd minimiser;    // where the global minimum is
  double minimum = 0.0;         // its value
};

// Σ_{k<d-1} 100 (x_{k+1} - x_k²)² + (1 - x_k)²: a curved narrow valley. Min 0 at (1, ..., 1).
double rosenbrock(const Eigen::VectorXd& x);
// 10 d + Σ (x_k² - 10 cos 2π x_k): a bowl covered in ~10^d local minima. Min 0 at 0.
double rastrigin(const Eigen::VectorXd& x);
// -20 exp(-0.2 sqrt(mean x_k²)) - exp(mean cos 2π x_k) + 20 + e: flat outside, one deep
// hole, many small dips. Min 0 at 0.
double ackley(const Eigen::VectorXd& x);
// Σ (x_k - s_k)²: the easy case, with the minimum off the box's centre and off any grid.
double shifted_sphere(const Eigen::VectorXd& x, const Eigen::VectorXd& shift);

// Box [-5, 10]^d (Rosenbrock), [-5.12, 5.12]^d (Rastrigin), [-32.768, 32.768]^d (Ackley),
// [-5, 5]^d with shift s_k = 1.234 - 0.71 k (shifted sphere). dim >= 1 (Rosenbrock >= 2).
TestProblem RosenbrockProblem(int dim);
TestProblem RastriginProblem(int dim);
TestProblem AckleyProblem(int dim);
TestProblem ShiftedSphereProblem(int dim);
// The shifted sphere in log10 coordinates on the log-scale box [1e-3, 1e4]^d, minimum at
// x_k = 10^(s_k) with s_k = 1.234 - 0.71 k: the shape of an (C, σ) search.
TestProblem LogShiftedSphereProblem(int dim);

}  // namespace thermodrift::optim
