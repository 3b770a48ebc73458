// ε-SVR: options, the trainer that runs the solver, and the decision function it returns.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "svr_kernel.hpp"
#include "svr_nystrom.hpp"
#include "svr_solver.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/models/svr.hpp"

namespace thermodrift {

bool SvrOptions::IsValid(std::string* error) const {
  const Invalid fail(error);
  if (!(std::isfinite(C) && C > 0)) return fail(fmt::format("C must be a positive number, not {}", C));
  if (!(std::isfinite(gamma) && gamma > 0))
    return fail(fmt::format("gamma must be a positive number, not {}", gamma));
  if (!(std::isfinite(epsilon) && epsilon >= 0))
    return fail(fmt::format("epsilon must be a number >= 0, not {}", epsilon));
  if (!(std::isfinite(tolerance) && tolerance > 0))
    return fail(fmt::format("tolerance must be a positive number, not {}", tolerance));
  if (!(std::isfinite(cache_mb) && cache_mb > 0))
    return fail(fmt::format("cache_mb must be a positive number, not {}", cache_mb));
  if (max_iterations < 1) return fail(fmt::format("max_iterations must be >= 1, not {}", max_iterations));
  if (threads < 1 || threads > 256) return fail(fmt::format("threads must be in 1..256, not {}", threads));
  if (landmarks < 1) return fail("landmarks must be >= 1");
  if (!(std::isfinite(landmark_residual) && landmark_residual > 0 && landmark_residual < 1)) {
    return fail(fmt::format("landmark_residual must be in (0, 1), not {}", landmark_residual));
  }
  if (low_rank_landmarks < 1) return fail("low_rank_landmarks must be >= 1");
  if (!(std::isfinite(low_rank_residual) && low_rank_residual > 0 && low_rank_residual < 1)) {
    return fail(fmt::format("low_rank_residual must be in (0, 1), not {}", low_rank_residual));
  }
  return true;
}

const char* to_string(SvrApproximation approximation) {
  switch (approximation) {
    case SvrApproximation::automatic: return "auto";
    case SvrApproximation::exact: return "exact";
    case SvrApproximation::nystrom: return "nystrom";
    case SvrApproximation::low_rank: return "low-rank";
  }
  return "unknown";
}

SvrApproximation svr_approximation_from_string(const std::string& text) {
  for (const auto approximation : {SvrApproximation::automatic, SvrApproximation::exact, SvrApproximation::nystrom,
                                   SvrApproximation::low_rank}) {
    if (text == to_string(approximation)) return approximation;
  }
  throw UsageError(fmt::format("unknown kernel approximation '{}' (expected auto, exact, nystrom or low-rank)", text));
}

const char* to_string(SvrTermination termination) {
  switch (termination) {
    case SvrTermination::converged: return "converged";
    case SvrTermination::iteration_limit: return "iteration_limit";
  }
  return "unknown";
}

namespace {
double rbf_decision(const RbfDecisionFunction& f, const double* x, svr_detail::RbfSumFunction sum) {
  const auto features = static_cast<std::size_t>(f.support_vectors.cols());
  constexpr std::size_t kFewFeatures = 32;
  const double* columns[kFewFeatures];
  std::vector<const double*> many;
  const double** column = columns;
  if (features > kFewFeatures) {
    many.resize(features);
    column = many.data();
  }
  // Column-major: each feature's values of all vectors are contiguous.
  for (std::size_t j = 0; j < features; ++j) column[j] = f.support_vectors.col(static_cast<Eigen::Index>(j)).data();
  return f.bias + sum(column, features, x, f.gamma, f.coefficients.data(),
                      static_cast<std::size_t>(f.support_vectors.rows()));
}
}  // namespace

double RbfDecisionFunction::operator()(const double* x) const { return rbf_decision(*this, x, svr_detail::rbf_sum); }

double RbfDecisionFunction::fast(const double* x) const { return rbf_decision(*this, x, svr_detail::rbf_sum_fast); }

const char* RbfDecisionFunction::fast_arithmetic() { return svr_detail::rbf_sum_fast_arithmetic(); }

Eigen::VectorXd RbfDecisionFunction::predict(const Eigen::MatrixXd& samples) const {
  if (samples.cols() != support_vectors.cols() && support_vectors.rows() > 0) {
    throw UsageError(fmt::format("predict: samples have {} features, the model {}", samples.cols(),
                                 support_vectors.cols()));
  }
  Eigen::VectorXd result(samples.rows());
  Eigen::VectorXd row(samples.cols());
  for (Eigen::Index r = 0; r < samples.rows(); ++r) {
    row = samples.row(r).transpose();
    result(r) = (*this)(row.data());
  }
  return result;
}

double RbfDecisionFunction::primal_objective(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets,
                                             double C, double epsilon) const {
  if (samples.rows() != targets.size()) {
    throw UsageError(fmt::format("primal objective: {} samples but {} targets", samples.rows(), targets.size()));
  }
  const Eigen::MatrixXd& v = support_vectors;
  double norm = 0;
  for (Eigen::Index a = 0; a < v.rows(); ++a) {
    for (Eigen::Index b = 0; b < v.rows(); ++b) {
      norm += coefficients(a) * coefficients(b) * std::exp(-gamma * (v.row(a) - v.row(b)).squaredNorm());
    }
  }
  const Eigen::ArrayXd loss = ((targets - predict(samples)).array().abs() - epsilon).max(0.0);
  return 0.5 * norm + C * loss.sum();
}

std::string SvrSummary::BriefReport() const {
  if (approximation == SvrApproximation::nystrom || approximation == SvrApproximation::low_rank) {
    return fmt::format("ε-SVR {} ({}, {} landmarks, mean kernel residual {:.2g}): {} Newton steps, dual objective {:.9g}, "
                       "gradient norm {:.3g}, {} samples outside the tube, {:.3f} s",
                       to_string(termination), approximation == SvrApproximation::low_rank ? "low rank" : "Nyström",
                       landmarks, kernel_residual, iterations, dual_objective, max_violation,
                       support_vectors, seconds);
  }
  return fmt::format("ε-SVR {}: {} iterations, dual objective {:.9g}, max KKT violation {:.3g}, {} SV ({} at C), "
                     "{} kernel columns{}, {:.3f} s",
                     to_string(termination), iterations, dual_objective, max_violation, support_vectors,
                     bounded_support_vectors, kernel_columns, warm_started ? ", warm start" : "", seconds);
}

SvrDataset::SvrDataset(Eigen::MatrixXd samples, double distance_budget_mb) : samples_(std::move(samples)) {
  const double n = static_cast<double>(samples_.rows());
  if (distance_budget_mb > 0 && n * n * sizeof(double) <= distance_budget_mb * 1024.0 * 1024.0) {
    const Eigen::Index size = samples_.rows();
    const Eigen::Index features = samples_.cols();
    // Sample-major, so that each pair reads two contiguous rows; the features summed in
    // order, as the kernel sums them when it computes a column from the samples.
    const Eigen::MatrixXd by_sample = samples_.transpose();
    distances_.resize(size, size);
    for (Eigen::Index column = 0; column < size; ++column) {
      const double* at_column = by_sample.col(column).data();
      distances_(column, column) = 0;
      for (Eigen::Index row = column + 1; row < size; ++row) {
        const double* at_row = by_sample.col(row).data();
        double squared = 0;
        for (Eigen::Index f = 0; f < features; ++f) {
          const double difference = at_row[f] - at_column[f];
          squared += difference * difference;
        }
        distances_(row, column) = squared;
        distances_(column, row) = squared;
      }
    }
  }
}

SvrTrainer::SvrTrainer(SvrOptions options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw UsageError("SVR options: " + error);
}

SvrFit SvrTrainer::train(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets) const {
  return train(SvrDataset(samples), targets);
}

SvrFit SvrTrainer::train(const SvrDataset& data, const Eigen::VectorXd& targets,
                         const SvrFit* warm_start) const {
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index size = targets.size();
  if (size == 0) throw UsageError("SVR: no training samples");
  if (static_cast<Eigen::Index>(data.size()) != size) {
    throw UsageError(fmt::format("SVR: {} samples but {} targets", data.size(), size));
  }
  if (!data.samples().allFinite() || !targets.allFinite()) {
    throw UsageError("SVR: samples and targets must be finite numbers");
  }
  if (size > 1'000'000'000) throw UsageError("SVR: too many samples");
  if (options_.approximation == SvrApproximation::nystrom ||
      (options_.approximation == SvrApproximation::automatic && data.size() > options_.exact_limit)) {
    return svr_detail::train_nystrom(data, targets, options_);
  }
  const bool warm = warm_start && warm_start->alpha.size() > 0;
  if (!warm && (options_.approximation == SvrApproximation::low_rank ||
                options_.approximation == SvrApproximation::automatic)) {
    if (auto fit = svr_detail::train_low_rank(data, targets, options_)) return std::move(*fit);
  }

  svr_detail::WorkerPool pool(options_.threads);
  svr_detail::RbfKernel kernel(data, options_.gamma, pool);
  svr_detail::KernelCache cache(kernel, options_.cache_mb);
  svr_detail::SmoSettings settings;
  settings.C = options_.C;
  settings.epsilon = options_.epsilon;
  settings.tolerance = options_.tolerance;
  settings.shrinking = options_.shrinking;
  settings.max_iterations = options_.max_iterations;
  settings.stop = options_.stop;

  svr_detail::SmoSolution solution;
  if (warm) {
    if (warm_start->alpha.size() != size || warm_start->alpha_star.size() != size || !(warm_start->C > 0)) {
      throw UsageError(fmt::format("SVR warm start comes from {} samples, this fit has {}",
                                   warm_start->alpha.size(), size));
    }
    // Scaling by C/C_old keeps Σ(α - α*) = 0 and puts every α in [0, C].
    const double scale = std::min(1.0, options_.C / warm_start->C);
    const Eigen::VectorXd alpha = (warm_start->alpha * scale).cwiseMax(0.0).cwiseMin(options_.C);
    const Eigen::VectorXd alpha_star = (warm_start->alpha_star * scale).cwiseMax(0.0).cwiseMin(options_.C);
    solution = svr_detail::solve_svr_dual(targets, settings, kernel, cache, pool, &alpha, &alpha_star);
  } else {
    solution = svr_detail::solve_svr_dual(targets, settings, kernel, cache, pool);
  }

  SvrFit fit;
  const Eigen::VectorXd beta = solution.alpha - solution.alpha_star;
  std::size_t support = 0, bounded = 0;
  for (Eigen::Index i = 0; i < size; ++i) {
    if (beta(i) != 0) {
      ++support;
      if (std::abs(beta(i)) >= options_.C) ++bounded;
    }
  }
  fit.function.gamma = options_.gamma;
  fit.function.bias = -solution.rho;
  fit.function.support_vectors.resize(static_cast<Eigen::Index>(support), data.samples().cols());
  fit.function.coefficients.resize(static_cast<Eigen::Index>(support));
  Eigen::Index next = 0;
  for (Eigen::Index i = 0; i < size; ++i) {
    if (beta(i) == 0) continue;
    fit.function.support_vectors.row(next) = data.samples().row(i);
    fit.function.coefficients(next) = beta(i);
    ++next;
  }
  fit.summary.termination =
      solution.converged ? SvrTermination::converged : SvrTermination::iteration_limit;
  fit.summary.iterations = solution.iterations;
  fit.summary.dual_objective = solution.objective;
  fit.summary.max_violation = solution.max_violation;
  fit.summary.support_vectors = support;
  fit.summary.bounded_support_vectors = bounded;
  fit.summary.kernel_columns = cache.columns_computed();
  fit.summary.warm_started = warm;
  fit.alpha = std::move(solution.alpha);
  fit.alpha_star = std::move(solution.alpha_star);
  fit.C = options_.C;
  fit.summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return fit;
}

}  // namespace thermodrift
