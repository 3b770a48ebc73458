// Internal to the ε-SVR trainer: the SMO-type decomposition solver of the dual.
#pragma once

#include <Eigen/Dense>

#include "svr_kernel.hpp"
#include "thermodrift/stop_token.hpp"

namespace thermodrift::svr_detail {

struct SmoSettings {
  double C = 1;
  double epsilon = 0.1;
  double tolerance = 1e-3;
  bool shrinking = true;
  long max_iterations = 0;
  StopToken stop;  // asked every 1000 steps at most: throws Interrupted
};

struct SmoSolution {
  Eigen::VectorXd alpha;       // α_i
  Eigen::VectorXd alpha_star;  // α_i^*
  double rho = 0;              // f(x) = Σ (α_i - α_i^*) K(x_i, x) - rho, as libsvm
  double objective = 0;        // ½ αᵀQα + pᵀα of the 2n-variable problem
  double max_violation = 0;    // m(α) - M(α) over all variables at the end
  long iterations = 0;
  bool converged = false;
};

// Solves the ε-SVR dual for `targets` (docs/svr.md and the comment in svr_solver.cpp).
// Starts from (alpha, alpha_star) when given; they must be feasible: in [0, C] and with
// Σ α_i - α_i^* = 0. Permutes the kernel's positions (the solution is in sample order).
SmoSolution solve_svr_dual(const Eigen::VectorXd& targets, const SmoSettings& settings,
                           RbfKernel& kernel, KernelCache& cache, WorkerPool& pool,
                           const Eigen::VectorXd* alpha = nullptr,
                           const Eigen::VectorXd* alpha_star = nullptr);

}  // namespace thermodrift::svr_detail
