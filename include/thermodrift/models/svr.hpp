// ε-support-vector regression with the RBF kernel, solved by our own SMO-type
// decomposition solver (docs/svr.md). A trainer (options, checked on construction)
// produces a fit whose `function` is a plain value: support vectors, coefficients, bias.
//
//   SvrTrainer trainer(SvrOptions{.C = 215, .gamma = 0.046, .epsilon = 0.1});
//   SvrFit fit = trainer.train(samples, targets);
//   double drift = fit.function(row_pointer);
//
// For many fits on the same samples (tuning over C and γ), build an SvrDataset once:
// it keeps the samples (and, when they fit the budget, all squared distances) so that
// each fit only evaluates exp(-γ d²); pass a previous fit to warm-start from its α.
#pragma once

#include <cstddef>
#include <cmath>
#include <memory>
#include <string>

#include <Eigen/Dense>

#include "thermodrift/stop_token.hpp"

namespace thermodrift {

// The RBF kernel's width σ, on standardized features, and libsvm's γ = 1/(2σ²): tuning
// and the CLI speak σ, the kernel and the model file γ (the file writes σ beside it for
// people). The one place they are converted.
inline double gamma_of_sigma(double sigma) { return 1.0 / (2.0 * sigma * sigma); }
inline double sigma_of_gamma(double gamma) { return std::sqrt(1.0 / (2.0 * gamma)); }

// How a fit treats the kernel matrix:
// - `exact`: SMO on the n × n kernel, columns cached;
// - `nystrom`: through a Nyström factor of rank ≤ `landmarks` (docs/svr.md, "Full-rate
//   logs": for logs the exact solver takes minutes or more on);
// - `low_rank`: through a pivoted-Cholesky factor when the kernel matrix *is* of rank
//   ≤ `low_rank_landmarks` to within `low_rank_residual` (the factor then loses nothing:
//   the fit is the exact one, found in the primal), by SMO otherwise. Wide kernels on few
//   features are of low rank, and there SMO needs 10⁵-10⁶ steps at large C (docs/svr.md);
// - `automatic` (the default): `low_rank` up to `exact_limit` samples, `nystrom` beyond.
// A fit's summary says which ran (exact, nystrom or low_rank).
enum class SvrApproximation { automatic, exact, nystrom, low_rank };

const char* to_string(SvrApproximation approximation);
SvrApproximation svr_approximation_from_string(const std::string& text);  // throws UsageError

struct SvrOptions {
  double C = 1.0;                 // penalty on points outside the tube (libsvm -c)
  double gamma = 0.5;             // RBF exp(-gamma ||x-x'||^2); gamma = 1/(2 sigma^2) (libsvm -g)
  double epsilon = 0.1;           // half-width of the insensitive tube (libsvm -p)
  double tolerance = 1e-3;        // stopping tolerance on the maximal KKT violation (libsvm -e)
  double cache_mb = 200;          // kernel-column cache budget in MiB (libsvm -m); at least two columns are kept
  bool shrinking = true;          // drop variables that sit at a bound from the working set (libsvm -h 1)
  long max_iterations = 400'000; // cap on SMO steps (~1 s of CPU at n = 2271, C = 1e4, γ = 100: docs/svr.md); reaching it gives SvrTermination::iteration_limit
  int threads = 1;                // threads for kernel columns inside one fit (used only for long columns)
  StopToken stop;                 // asked at the start of a fit and every 1000 SMO steps at most: throws Interrupted
  SvrApproximation approximation = SvrApproximation::automatic;
  std::size_t exact_limit = 30'000;  // automatic: the exact solver up to this many samples
  std::size_t landmarks = 512;       // Nyström: the largest rank of the factor (its landmarks)
  double landmark_residual = 1e-6;   // Nyström: no landmark once every K(x,x) − φ(x)ᵀφ(x) is below this
  std::size_t low_rank_landmarks = 64;  // low_rank: the largest rank taken for a complete factor
  double low_rank_residual = 1e-12;     // low_rank: the residual below which the factor counts as complete

  // True when every field is usable; otherwise false with a one-line reason in *error.
  bool IsValid(std::string* error) const;
};

enum class SvrTermination {
  converged,        // maximal KKT violation below `tolerance`
  iteration_limit,  // stopped at `max_iterations`: the function is usable but not optimal
};

const char* to_string(SvrTermination termination);

// f(x) = sum_i coefficients_i exp(-gamma ||sv_i - x||^2) + bias. A plain value.
struct RbfDecisionFunction {
  Eigen::MatrixXd support_vectors;  // one row per support vector
  Eigen::VectorXd coefficients;     // alpha_i - alpha_i^*, one per support vector
  double bias = 0;                  // NOTE sign: libsvm stores rho with f = sum - rho; ours is +bias = -rho
  double gamma = 0;                 // kernel width of the fit

  // x has support_vectors.cols() entries. The same bits on every x86-64: fits, tuning and
  // every figure written to a file use it.
  double operator()(const double* x) const;
  Eigen::VectorXd predict(const Eigen::MatrixXd& samples) const;  // one row per sample, as operator()
  // The field's evaluation: the same value with the widest arithmetic this CPU has
  // (AVX-512 or AVX2 with fused multiply-adds), 2-3x faster; it differs from operator()
  // by a few 1e-17 of Σ|coefficients|, in bits that depend on the CPU.
  double fast(const double* x) const;
  static const char* fast_arithmetic();  // which: "avx512-fma", "avx2-fma" or "exact"
  // ½‖f‖²_H + C·Σ max(0, |y − f(x)| − ε) on (samples, targets): the problem every solver
  // here minimizes, judged on this function (its RKHS norm from its own vectors), so fits
  // by different solvers or approximations compare on one scale. O(vectors²) kernels.
  double primal_objective(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets, double C,
                          double epsilon) const;
};

struct SvrSummary {
  SvrTermination termination = SvrTermination::converged;
  long iterations = 0;                      // SMO steps (libsvm's "#iter")
  double dual_objective = 0;                // libsvm's "obj": ½αᵀQα + pᵀα of the 2n-variable dual
  double max_violation = 0;                 // maximal KKT violation at the end (≤ tolerance when converged)
  std::size_t support_vectors = 0;          // samples with alpha_i - alpha_i^* != 0 (libsvm "nSV")
  std::size_t bounded_support_vectors = 0;  // of those, |alpha_i - alpha_i^*| = C (libsvm "nBSV")
  std::size_t kernel_columns = 0;           // kernel columns computed (cache misses)
  bool warm_started = false;                // started from a previous fit's α
  double seconds = 0;                       // wall time of the fit
  SvrApproximation approximation = SvrApproximation::exact;  // which solver ran (never automatic)
  std::size_t landmarks = 0;                // Nyström, low rank: the factor's rank (= support vectors of the function)
  double kernel_residual = 0;               // Nyström, low rank: mean of K(x,x) − φ(x)ᵀφ(x) over the samples (exact: 0)

  std::string BriefReport() const;  // one line
};

struct SvrFit {
  RbfDecisionFunction function;
  SvrSummary summary;
  // The full dual solution, one entry per training sample, for a warm start:
  Eigen::VectorXd alpha;       // α_i   (points above the tube)
  Eigen::VectorXd alpha_star;  // α_i^* (points below the tube)
  double C = 0;                // the penalty the α above satisfy 0 ≤ α ≤ C for
};

// The samples of a data set prepared for repeated fits. Squared distances are
// computed once and stored when n² doubles fit in `distance_budget_mb`; otherwise
// they are recomputed per kernel column from the samples (cheap for few features).
class SvrDataset {
 public:
  explicit SvrDataset(Eigen::MatrixXd samples, double distance_budget_mb = 0);

  const Eigen::MatrixXd& samples() const { return samples_; }
  std::size_t size() const { return static_cast<std::size_t>(samples_.rows()); }
  bool has_distances() const { return distances_.size() > 0; }
  // ||x_i - x_j||², one column per sample; empty unless has_distances().
  const Eigen::MatrixXd& squared_distances() const { return distances_; }

 private:
  Eigen::MatrixXd samples_;    // n × d
  Eigen::MatrixXd distances_;  // n × n or empty
};

class SvrTrainer {
 public:
  explicit SvrTrainer(SvrOptions options);  // throws UsageError if !options.IsValid()

  const SvrOptions& options() const { return options_; }

  // One fit. Throws UsageError when sizes disagree or the data is empty or not finite.
  SvrFit train(const Eigen::MatrixXd& samples, const Eigen::VectorXd& targets) const;
  // A fit on a prepared data set; `warm_start`, if given, must come from a fit on the
  // same samples (any C, γ, ε): its α scaled into [0, C] is the starting point.
  SvrFit train(const SvrDataset& data, const Eigen::VectorXd& targets,
               const SvrFit* warm_start = nullptr) const;

 private:
  SvrOptions options_;
};

}  // namespace thermodrift
