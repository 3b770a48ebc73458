// Internal to the ε-SVR trainer: the Nyström fit for logs too long for the exact solver
// (docs/svr.md, "Full-rate logs").
//
// The kernel matrix is replaced by a low-rank factor from a pivoted (incomplete)
// Cholesky factorization, K ≈ L Lᵀ with L of n × r: each step takes as a landmark the
// sample whose kernel the landmarks so far explain least (the largest residual of the
// diagonal), until r reaches `landmarks` or every residual is below `landmark_residual`.
// Then φ_i = L_i is a finite feature map, exact on the landmarks, and the ε-SVR becomes
// a linear ε-SVR in r + 1 unknowns (w, b), solved in the primal by Newton's method on the
// ε-insensitive loss smoothed over a width δ shrunk to 10⁻⁸ (coordinate descent in the
// dual, as liblinear's, was tried: at C = 215 it was still 0.2 % off the exact objective
// after 20,000 passes).
// Since φ(x) = L_m⁻¹ k_m(x) for any x (L_m: the landmarks' rows of L, lower triangular),
// f(x) = wᵀφ(x) + b = Σ_j α_j K(x, z_j) + b with α = L_m⁻ᵀ w: an ordinary RBF decision
// function on the landmarks, so evaluate, compensate and export take it unchanged.
#pragma once

#include <cstddef>
#include <optional>

#include <Eigen/Dense>

#include "thermodrift/models/svr.hpp"

namespace thermodrift::svr_detail {

// Newton steps per smoothing width before the fit stops as iteration_limit.
inline constexpr int kMaxNewtonSteps = 100;

// The Nyström fit. `summary.iterations` counts Newton steps, `summary.max_violation` is the
// norm of the last smoothed objective's gradient, `summary.dual_objective` minus the primal
// objective ½‖w‖² + C·Σ max(0, |y − f| − ε) (equal to the dual's at the optimum, as libsvm's
// "obj"), `summary.support_vectors` the samples outside the tube.
SvrFit train_nystrom(const SvrDataset& data, const Eigen::VectorXd& targets, const SvrOptions& options);

// The same fit when at most `low_rank_landmarks` landmarks explain every sample's kernel
// to within `low_rank_residual` (then it is the exact fit; summary.approximation says
// low_rank); otherwise nothing (the factor's cost, r kernel columns, is lost).
std::optional<SvrFit> train_low_rank(const SvrDataset& data, const Eigen::VectorXd& targets,
                                     const SvrOptions& options);

}  // namespace thermodrift::svr_detail
