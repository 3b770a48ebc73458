#include "thermodrift/models/svr_reduce.hpp"

#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "thermodrift/error.hpp"

namespace thermodrift {

bool ReduceOptions::IsValid(std::string* error) const {
  const Invalid fail(error);
  if (max_vectors < 1) return fail("the reduced set needs at least 1 vector");
  if (max_points < 2) return fail("the reduced set needs at least 2 evaluation points");
  if (max_candidates < 1) return fail("the reduced set needs at least 1 candidate centre");
  return true;
}

namespace {

// At most `limit` rows of `rows`, evenly strided, first row kept, in order.
Eigen::MatrixXd strided_rows(const Eigen::MatrixXd& rows, std::size_t limit) {
  const auto n = static_cast<std::size_t>(rows.rows());
  if (n <= limit) return rows;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(limit), rows.cols());
  for (std::size_t i = 0; i < limit; ++i) out.row(static_cast<Eigen::Index>(i)) = rows.row(static_cast<Eigen::Index>(i * n / limit));
  return out;
}

// exp(-γ ||x_i - c_j||²), one row per point, one column per centre.
Eigen::MatrixXd kernel_matrix(const Eigen::MatrixXd& points, const Eigen::MatrixXd& centres, double gamma) {
  const Eigen::VectorXd point_norms = points.rowwise().squaredNorm();
  const Eigen::RowVectorXd centre_norms = centres.rowwise().squaredNorm().transpose();
  Eigen::MatrixXd kernel = -2.0 * points * centres.transpose();
  kernel.colwise() += point_norms;
  kernel.rowwise() += centre_norms;
  // Cancellation can leave a tiny negative distance: a distance is never below 0.
  return (-gamma * kernel.cwiseMax(0.0)).array().exp().matrix();
}

// Coefficients and bias by least squares for fixed centres, and the mean square residual.
struct LeastSquaresFit {
  Eigen::MatrixXd centres;
  Eigen::VectorXd coefficients;
  double bias = 0;
  Eigen::VectorXd residual;  // y − fit at the points
  Eigen::MatrixXd kernel;    // at the points, one column per centre
  double mse = 0;
};

LeastSquaresFit fit_at(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, Eigen::MatrixXd centres, double gamma) {
  LeastSquaresFit fit;
  fit.centres = std::move(centres);
  fit.kernel = kernel_matrix(x, fit.centres, gamma);
  const auto k = fit.centres.rows();
  Eigen::MatrixXd design(x.rows(), k + 1);
  design.leftCols(k) = fit.kernel;
  design.col(k).setOnes();
  const Eigen::VectorXd solution = design.colPivHouseholderQr().solve(y);
  fit.coefficients = solution.head(k);
  fit.bias = solution(k);
  fit.residual = y - design * solution;
  fit.mse = fit.residual.squaredNorm() / static_cast<double>(x.rows());
  return fit;
}

// Moves the centres off the sample points (pre-images) by gradient descent on the mean
// square residual, the coefficients refitted by least squares at every step (variable
// projection: the gradient at the least-squares coefficients is the partial one). Steps
// of Barzilai-Borwein length, halved until the residual falls; stops when it no longer does.
LeastSquaresFit refine_centres(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, LeastSquaresFit fit,
                               double gamma, std::size_t iterations, const StopToken& stop) {
  const double n = static_cast<double>(x.rows());
  // ∂mse/∂z_k = −(4γ/n)·β_k·Σ_i r_i K_ik (x_i − z_k)
  const auto gradient = [&](const LeastSquaresFit& at) {
    const Eigen::MatrixXd weighted = at.kernel.array().colwise() * at.residual.array();
    const Eigen::VectorXd sums = weighted.colwise().sum().transpose();
    Eigen::MatrixXd g = weighted.transpose() * x - sums.asDiagonal() * at.centres;
    return Eigen::MatrixXd((-4.0 * gamma / n) * (at.coefficients.asDiagonal() * g));
  };
  Eigen::MatrixXd g = gradient(fit);
  double step = 0;
  {
    // First step: one that would move the centres by 1 % of a kernel width.
    const double norm = g.norm();
    if (!(norm > 0)) return fit;
    step = 0.01 / std::sqrt(2.0 * gamma) / norm;
  }
  for (std::size_t iteration = 0; iteration < iterations; ++iteration) {
    stop.throw_if_requested("model compression");
    bool improved = false;
    for (int halvings = 0; halvings < 30; ++halvings, step /= 2) {
      LeastSquaresFit trial = fit_at(x, y, fit.centres - step * g, gamma);
      if (trial.mse < fit.mse) {
        const Eigen::MatrixXd moved = trial.centres - fit.centres;
        const Eigen::MatrixXd g_new = gradient(trial);
        const double curvature = (moved.array() * (g_new - g).array()).sum();
        if (curvature > 0) step = moved.squaredNorm() / curvature;
        const bool negligible = fit.mse - trial.mse <= 1e-9 * fit.mse;
        fit = std::move(trial);
        g = g_new;
        improved = !negligible;
        break;
      }
    }
    if (!improved) break;
  }
  return fit;
}

}  // namespace

ReducedSet reduce_rbf(const RbfDecisionFunction& function, const Eigen::MatrixXd& points,
                      const ReduceOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw UsageError(error);
  if (points.cols() != function.support_vectors.cols()) {
    throw UsageError(fmt::format("reduce: points have {} features, the model {}", points.cols(),
                                 function.support_vectors.cols()));
  }
  if (points.rows() < 2) throw UsageError("reduce: at least 2 evaluation points are needed");
  ReducedSet result;
  result.original_vectors = static_cast<std::size_t>(function.support_vectors.rows());
  const Eigen::MatrixXd x = strided_rows(points, options.max_points);
  result.points = static_cast<std::size_t>(x.rows());
  const Eigen::VectorXd y = function.predict(x);
  if (result.original_vectors <= options.max_vectors) {
    result.function = function;
    return result;
  }

  // Kernel matching pursuit with back-fitting: each step takes the candidate column that
  // best explains what the chosen columns (and the constant) leave of y, measured after
  // projecting it on their orthogonal complement, so a column that repeats the chosen
  // ones scores nothing.
  const Eigen::MatrixXd candidates = strided_rows(x, options.max_candidates);
  const Eigen::MatrixXd kernel = kernel_matrix(x, candidates, function.gamma);
  const auto n = x.rows();
  const Eigen::VectorXd constant = Eigen::VectorXd::Constant(n, 1.0 / std::sqrt(static_cast<double>(n)));
  Eigen::MatrixXd projected = kernel - constant * (constant.transpose() * kernel);
  Eigen::VectorXd residual = y - constant * constant.dot(y);
  const Eigen::VectorXd original_norms = kernel.colwise().squaredNorm().transpose();
  std::vector<bool> used(static_cast<std::size_t>(candidates.rows()), false);
  std::vector<Eigen::Index> chosen;
  while (chosen.size() < options.max_vectors) {
    options.stop.throw_if_requested("model compression");
    const Eigen::VectorXd norms = projected.colwise().squaredNorm().transpose();
    const Eigen::VectorXd dots = projected.transpose() * residual;
    Eigen::Index best = -1;
    double best_score = 0;
    for (Eigen::Index j = 0; j < candidates.rows(); ++j) {
      // A column less than 3e-9 of its norm outside the chosen span carries no new direction
      // that least squares could use safely. Wide kernels (σ of 10-20 standardized units,
      // common on drift data) are numerically low-rank: on the demo's log, 8-14 vectors
      // reproduce the SVR to 1e-4 °/h; a stricter limit (1e-5 of the norm) kept 5-6 and cost
      // up to 7 % of held-out MSE.
      if (used[static_cast<std::size_t>(j)] || !(norms(j) > 1e-17 * original_norms(j))) continue;
      const double score = dots(j) * dots(j) / norms(j);
      if (score > best_score) best = j, best_score = score;
    }
    if (best < 0) break;
    used[static_cast<std::size_t>(best)] = true;
    chosen.push_back(best);
    const Eigen::VectorXd direction = projected.col(best) / std::sqrt(norms(best));
    residual -= direction * direction.dot(residual);
    projected -= direction * (direction.transpose() * projected);
  }

  Eigen::MatrixXd centres(static_cast<Eigen::Index>(chosen.size()), x.cols());
  for (std::size_t c = 0; c < chosen.size(); ++c) centres.row(static_cast<Eigen::Index>(c)) = candidates.row(chosen[c]);
  LeastSquaresFit fitted = fit_at(x, y, centres, function.gamma);
  if (options.refine_iterations > 0) {
    fitted = refine_centres(x, y, std::move(fitted), function.gamma, options.refine_iterations, options.stop);
  }
  result.function.gamma = function.gamma;
  result.function.support_vectors = fitted.centres;
  result.function.coefficients = fitted.coefficients;
  result.function.bias = fitted.bias;
  const Eigen::VectorXd change = result.function.predict(x) - y;
  result.rms_change = std::sqrt(change.squaredNorm() / static_cast<double>(n));
  result.max_change = change.cwiseAbs().maxCoeff();
  if (!std::isfinite(result.rms_change)) {
    throw Error("the reduced set is not finite: the model's kernel matrix is singular at these points");
  }
  return result;
}

}  // namespace thermodrift
