#include "svr_nystrom.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "svr_kernel.hpp"

namespace thermodrift::svr_detail {

namespace {

struct Factor {
  Eigen::MatrixXd rows;            // n × r: φ_i = rows.row(i), K ≈ rows·rowsᵀ
  std::vector<Eigen::Index> pivots;  // the landmarks, in the order taken
  double mean_residual = 0;        // trace(K − rows·rowsᵀ) / n
  double largest_residual = 0;     // max of K(x,x) − φ(x)ᵀφ(x) over the samples
};

// Pivoted Cholesky of the RBF kernel matrix, never forming it: one kernel column per landmark.
Factor pivoted_cholesky(const SvrDataset& data, const SvrOptions& options, WorkerPool& pool) {
  const auto n = static_cast<Eigen::Index>(data.size());
  const auto most = static_cast<Eigen::Index>(std::min<std::size_t>(options.landmarks, data.size()));
  RbfKernel kernel(data, options.gamma, pool);  // no swaps: positions are samples
  Factor factor;
  factor.rows.resize(n, most);
  Eigen::VectorXd residual = Eigen::VectorXd::Ones(n);
  Eigen::VectorXd column(n);
  Eigen::Index rank = 0;
  for (; rank < most; ++rank) {
    if (rank % 16 == 0) options.stop.throw_if_requested("SVR fit (kernel factor)");
    Eigen::Index pivot = 0;
    const double largest = residual.maxCoeff(&pivot);  // the first of equal residuals
    if (!(largest > options.landmark_residual)) break;
    kernel.column(static_cast<std::size_t>(pivot), 0, static_cast<std::size_t>(n), column.data());
    if (rank > 0) column.noalias() -= factor.rows.leftCols(rank) * factor.rows.row(pivot).head(rank).transpose();
    column /= std::sqrt(largest);
    factor.rows.col(rank) = column;
    residual -= column.cwiseAbs2();
    residual(pivot) = 0;
    factor.pivots.push_back(pivot);
  }
  factor.rows.conservativeResize(n, rank);
  factor.mean_residual = residual.cwiseMax(0.0).mean();
  factor.largest_residual = std::max(0.0, residual.maxCoeff());
  return factor;
}

struct LinearPrimal {
  Eigen::VectorXd v;        // (w, b): the weights on φ, the bias last
  double objective = 0;     // ½‖w‖² + C·Σ max(0, |y − φᵀw − b| − ε), the ε-SVR primal
  std::size_t outside = 0;  // samples outside the tube (nonzero β in the dual)
  long steps = 0;           // Newton steps over all smoothings
  double gradient_norm = 0; // of the last smoothing's objective, at the end
  bool converged = false;
};

// The ε-SVR primal in the r + 1 unknowns (w, b), by Newton's method on the hinge smoothed
// over a width δ (quadratic for 0 < |residual| − ε < δ), δ shrunk tenfold from 1 to 10⁻⁸
// with each solution the next start; the bias is not penalized, as in the exact dual.
LinearPrimal solve_linear_primal(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y, const SvrOptions& options) {
  const Eigen::Index n = phi.rows(), r = phi.cols();
  Eigen::MatrixXd x(n, r + 1);
  x.leftCols(r) = phi;
  x.col(r).setOnes();
  const double C = options.C, epsilon = options.epsilon;
  LinearPrimal result;
  result.v = Eigen::VectorXd::Zero(r + 1);
  result.v(r) = y.mean();
  // The smoothed objective from the residuals y − x·v: a trial step's residuals are the
  // current ones minus the step times x·direction, one product per direction however many
  // step lengths are tried (the products with x were most of the fit's time).
  auto value = [&](const Eigen::VectorXd& v, const Eigen::VectorXd& residual, double delta) {
    const Eigen::ArrayXd u = residual.array().abs() - epsilon;
    const Eigen::ArrayXd loss = (u <= 0).select(0.0, (u < delta).select(u.square() / (2 * delta), u - delta / 2));
    return 0.5 * v.head(r).squaredNorm() + C * loss.sum();
  };
  result.converged = true;
  Eigen::VectorXd residual(n), trial_residual(n), moved_by(n);
  for (double delta = 1.0; delta >= 1e-8 * 0.999; delta /= 10) {
    residual.noalias() = y - x * result.v;  // afresh at each width: no drift from the updates
    bool settled = false;
    for (int step = 0; step < kMaxNewtonSteps && !settled; ++step) {
      options.stop.throw_if_requested("SVR fit");
      Eigen::VectorXd gradient = Eigen::VectorXd::Zero(r + 1);
      gradient.head(r) = result.v.head(r);
      Eigen::MatrixXd hessian = Eigen::MatrixXd::Identity(r + 1, r + 1);
      hessian(r, r) = 0;  // the bias is not penalized
      Eigen::VectorXd slopes = Eigen::VectorXd::Zero(n);
      std::vector<Eigen::Index> curved;  // the samples in the smoothed hinge's quadratic zone
      for (Eigen::Index i = 0; i < n; ++i) {
        const double u = std::abs(residual(i)) - epsilon;
        if (u <= 0) continue;
        const double sign = residual(i) > 0 ? 1.0 : -1.0;
        if (u < delta) {
          slopes(i) = -C * sign * u / delta;
          curved.push_back(i);
        } else {
          slopes(i) = -C * sign;
        }
      }
      gradient.noalias() += x.transpose() * slopes;
      // Only the quadratic zone bends the objective: a few samples near the tube's edge
      // once δ is small, so the Hessian costs far less than a pass over all of them.
      if (!curved.empty()) {
        const Eigen::MatrixXd zone = x(curved, Eigen::all);
        hessian.selfadjointView<Eigen::Lower>().rankUpdate(zone.transpose(), C / delta);
        hessian.triangularView<Eigen::StrictlyUpper>() = hessian.transpose();
      }
      result.gradient_norm = gradient.norm();
      ++result.steps;
      // Newton's step, damped (Levenberg) when it does not descend: the hinge is piecewise
      // linear beyond δ, where the curvature the step assumes is only that of the penalty.
      const double before = value(result.v, residual, delta);
      bool moved = false;
      for (double damping = 0; damping <= 1e12 && !moved; damping = std::max(1e-6, damping * 100)) {
        const Eigen::MatrixXd damped = hessian + damping * Eigen::MatrixXd::Identity(r + 1, r + 1);
        const Eigen::VectorXd direction = -damped.ldlt().solve(gradient);
        if (!direction.allFinite()) continue;  // singular without damping: no sample bends the bias
        const double decrement = -gradient.dot(direction);
        if (!(decrement > 1e-13 * std::max(1.0, before))) {
          settled = damping == 0;  // at the minimum of this smoothing
          if (settled) break;
          continue;
        }
        moved_by.noalias() = x * direction;
        for (double length = 1; length > 1e-3; length /= 2) {
          const Eigen::VectorXd trial = result.v + length * direction;
          trial_residual = residual - length * moved_by;
          if (value(trial, trial_residual, delta) <= before - 1e-4 * length * decrement) {
            result.v = trial;
            residual.swap(trial_residual);
            moved = true;
            break;
          }
        }
      }
      if (!moved && !settled) break;  // no descent at this resolution: the next, finer smoothing goes on
    }
    result.converged = result.converged && settled;
  }
  const Eigen::ArrayXd u = (y - x * result.v).array().abs() - epsilon;
  result.objective = 0.5 * result.v.head(r).squaredNorm() + C * u.max(0.0).sum();
  result.outside = static_cast<std::size_t>((u > 0).count());
  return result;
}

SvrFit fit_on_factor(const SvrDataset& data, const Eigen::VectorXd& targets, const SvrOptions& options,
                     const Factor& factor, std::chrono::steady_clock::time_point start) {
  const auto rank = static_cast<Eigen::Index>(factor.pivots.size());
  const LinearPrimal primal = solve_linear_primal(factor.rows, targets, options);

  // α = L_m⁻ᵀ w, L_m the landmarks' rows of the factor (lower triangular in the order taken).
  Eigen::MatrixXd landmark_rows(rank, rank);
  for (Eigen::Index j = 0; j < rank; ++j) landmark_rows.row(j) = factor.rows.row(factor.pivots[static_cast<std::size_t>(j)]);
  const Eigen::VectorXd alpha =
      landmark_rows.triangularView<Eigen::Lower>().transpose().solve(primal.v.head(rank));

  SvrFit fit;
  fit.function.gamma = options.gamma;
  fit.function.bias = primal.v(rank);
  fit.function.support_vectors.resize(rank, data.samples().cols());
  for (Eigen::Index j = 0; j < rank; ++j) {
    fit.function.support_vectors.row(j) = data.samples().row(factor.pivots[static_cast<std::size_t>(j)]);
  }
  fit.function.coefficients = alpha;
  SvrSummary& summary = fit.summary;
  summary.termination = primal.converged ? SvrTermination::converged : SvrTermination::iteration_limit;
  summary.iterations = primal.steps;
  summary.dual_objective = -primal.objective;  // at the optimum the dual's value, as libsvm's "obj"
  summary.max_violation = primal.gradient_norm;
  summary.support_vectors = primal.outside;
  summary.kernel_columns = static_cast<std::size_t>(rank);
  summary.approximation = SvrApproximation::nystrom;
  summary.landmarks = static_cast<std::size_t>(rank);
  summary.kernel_residual = factor.mean_residual;
  fit.C = options.C;  // no α: a Nyström fit does not warm-start another
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return fit;
}

}  // namespace

SvrFit train_nystrom(const SvrDataset& data, const Eigen::VectorXd& targets, const SvrOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  WorkerPool pool(options.threads);
  return fit_on_factor(data, targets, options, pivoted_cholesky(data, options, pool), start);
}

std::optional<SvrFit> train_low_rank(const SvrDataset& data, const Eigen::VectorXd& targets,
                                     const SvrOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  WorkerPool pool(options.threads);
  SvrOptions probe = options;
  probe.landmarks = options.low_rank_landmarks;
  probe.landmark_residual = options.low_rank_residual;
  const Factor factor = pivoted_cholesky(data, probe, pool);
  if (factor.largest_residual > probe.landmark_residual) return std::nullopt;
  SvrFit fit = fit_on_factor(data, targets, probe, factor, start);
  fit.summary.approximation = SvrApproximation::low_rank;
  return fit;
}

}  // namespace thermodrift::svr_detail
