// The ε-SVR dual and its SMO-type decomposition solver.
//
// Training data (x_i, z_i), i = 1..n; kernel K_ij = exp(-γ ||x_i - x_j||²). The dual of
// ε-SVR is written, as in libsvm, as one problem in 2n variables
//   a = (α_1..α_n, α*_1..α*_n),  y = (+1..+1, -1..-1),  Q_st = y_s y_t K(s mod n, t mod n),
//
//   min_a  ½ aᵀ Q a + pᵀ a      with p = (ε - z_1..ε - z_n, ε + z_1..ε + z_n)
//   s.t.   yᵀ a = 0,  0 ≤ a_t ≤ C,
//
// i.e. ½ βᵀKβ - zᵀβ + ε Σ(α_i + α*_i) with β = α - α*, Σ β_i = 0, and the regression
// function is f(x) = Σ β_i K(x_i, x) - ρ. Both halves of a sample share one kernel
// column, so instead of the 2n-gradient G_t = p_t + (Qa)_t we keep one number per sample,
// the residual r_i = z_i - (Kβ)_i; then G_t = ε - y_t r_{t mod n}, and -y_t G_t is
// r - ε for α and r + ε for α*.
//
// Optimality (KKT): with I_up = {t : y_t = +1, a_t < C} ∪ {t : y_t = -1, a_t > 0} and
// I_low = {t : y_t = +1, a_t > 0} ∪ {t : y_t = -1, a_t < C},
//   m(a) = max_{I_up} -y_t G_t  ≤  M(a) = min_{I_low} -y_t G_t   (stop when m - M < tolerance).
// Each step picks i = argmax over I_up and j over I_low by the second-order rule of
// Fan, Chen & Lin (2005), minimising -(m + y_j G_j)² / (K_ii + K_jj - 2 K_ij), solves the
// two-variable subproblem exactly and clips it to the box. Shrinking drops samples whose
// two variables sit at bounds that cannot move (libsvm's rule); the residual of dropped
// samples is rebuilt from the "bounded part" Kβ_C (columns of variables at C, kept up to
// date) plus the free variables when they come back.
#include "svr_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace thermodrift::svr_detail {

namespace {

constexpr double kTau = 1e-12;  // curvature used when K_ii + K_jj - 2K_ij ≤ 0
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// One of the 2n variables: half 0 is α_sample (y = +1), half 1 is α*_sample (y = -1).
struct Variable {
  int sample = -1;
  int half = 0;
  double sign() const { return half == 0 ? 1.0 : -1.0; }
};

class SvrSmo {
 public:
  SvrSmo(const Eigen::VectorXd& targets, const SmoSettings& settings, const RbfKernel& kernel,
         KernelCache& cache, WorkerPool& pool)
      : size_(static_cast<int>(targets.size())),
        targets_(targets),
        C_(settings.C),
        epsilon_(settings.epsilon),
        settings_(settings),
        kernel_(kernel),
        cache_(cache),
        pool_(pool),
        alpha_(size_, 0.0),
        alpha_star_(size_, 0.0),
        residual_(size_),
        bounded_part_(size_, 0.0),
        up_offset_(size_),
        low_offset_(size_) {
    active_.resize(size_);
    for (int sample = 0; sample < size_; ++sample) active_[sample] = sample;
  }

  void start_from(const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star);
  SmoSolution solve();

 private:
  void refresh_offsets(int sample) {
    const double a = alpha_[sample], a_star = alpha_star_[sample];
    up_offset_[sample] = a_star > 0 ? epsilon_ : (a < C_ ? -epsilon_ : -kInfinity);
    low_offset_[sample] = a > 0 ? -epsilon_ : (a_star < C_ ? epsilon_ : kInfinity);
  }
  // Calls body(sample) for every active sample; a plain counted loop when all are active.
  template <typename Body>
  void for_active(Body&& body) const {
    if (all_active()) {
      for (int sample = 0; sample < size_; ++sample) body(sample);
    } else {
      for (int sample : active_) body(sample);
    }
  }
  double& value_of(Variable v) { return v.half == 0 ? alpha_[v.sample] : alpha_star_[v.sample]; }
  bool all_active() const { return static_cast<int>(active_.size()) == size_; }
  void find_first();
  bool select_working_set(Variable* first, Variable* second);
  void take_step(Variable first, Variable second);
  void shrink();
  void reconstruct_residual();
  void activate_all();
  std::pair<double, double> violation_bounds(const std::vector<int>& samples) const;

  int size_;
  const Eigen::VectorXd& targets_;
  double C_;
  double epsilon_;
  SmoSettings settings_;
  const RbfKernel& kernel_;
  KernelCache& cache_;
  WorkerPool& pool_;

  std::vector<double> alpha_;
  std::vector<double> alpha_star_;
  std::vector<double> residual_;      // z - Kβ, up to date on active samples
  std::vector<double> bounded_part_;  // K β_C, β_C = C·[α = C] - C·[α* = C], on all samples
  // Per sample, the offset of its best I_up candidate from r (max over its two halves of
  // -y G - r: +ε if α* > 0, else -ε if α < C, else -∞) and of its best I_low candidate
  // (min of -y G - r: -ε if α > 0, else +ε if α* < C, else +∞). The selection loops read
  // one number per sample instead of testing both halves.
  std::vector<double> up_offset_;
  std::vector<double> low_offset_;
  std::vector<int> active_;           // samples in the working problem, ascending
  bool unshrunk_ = false;

  // The first variable of the next working set, found while updating the residual.
  Variable first_;
  double first_value_ = -kInfinity;
  bool first_known_ = false;
};

void SvrSmo::start_from(const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star) {
  for (int sample = 0; sample < size_; ++sample) {
    alpha_[sample] = alpha(sample);
    alpha_star_[sample] = alpha_star(sample);
    refresh_offsets(sample);
  }
  for (int sample = 0; sample < size_; ++sample) residual_[sample] = targets_(sample);
  for (int sample = 0; sample < size_; ++sample) {
    const double beta = alpha_[sample] - alpha_star_[sample];
    const double bounded = (alpha_[sample] >= C_ ? C_ : 0.0) - (alpha_star_[sample] >= C_ ? C_ : 0.0);
    if (beta == 0 && bounded == 0) continue;
    const double* column = cache_.column(sample, active_, true);
    for (int row = 0; row < size_; ++row) {
      residual_[row] -= beta * column[row];
      bounded_part_[row] += bounded * column[row];
    }
  }
}

// m(a) = max over I_up of -y G, and M(a) = min over I_low of -y G, over `samples`.
std::pair<double, double> SvrSmo::violation_bounds(const std::vector<int>& samples) const {
  double largest_up = -kInfinity;
  double smallest_low = kInfinity;
  for (int sample : samples) {
    const double r = residual_[sample];
    if (alpha_[sample] < C_) largest_up = std::max(largest_up, r - epsilon_);
    if (alpha_star_[sample] > 0) largest_up = std::max(largest_up, r + epsilon_);
    if (alpha_[sample] > 0) smallest_low = std::min(smallest_low, r - epsilon_);
    if (alpha_star_[sample] < C_) smallest_low = std::min(smallest_low, r + epsilon_);
  }
  return {largest_up, smallest_low};
}

void SvrSmo::find_first() {
  double best = -kInfinity;
  int best_sample = -1;
  for_active([&](int sample) {
    const double value = residual_[sample] + up_offset_[sample];
    if (value > best) {
      best = value;
      best_sample = sample;
    }
  });
  first_value_ = best;
  first_ = best_sample < 0 ? Variable{} : Variable{best_sample, alpha_star_[best_sample] > 0 ? 1 : 0};
  first_known_ = true;
}

// Returns true when the active problem is optimal within the tolerance.
bool SvrSmo::select_working_set(Variable* first, Variable* second) {
  if (!first_known_) find_first();
  const double largest_up = first_value_;  // m(a)
  *first = first_;
  if (first_.sample < 0) return true;
  const double* first_column = cache_.column(first_.sample, active_, false);

  // For each sample only its I_low half with the smaller -y G can win: both share the
  // curvature K_ii + K_jj - 2 K_ij = 2 - 2 K_ij (K_ii = 1) and the larger gap wins.
  double smallest_low = kInfinity;  // M(a)
  double best_score = 0;            // (m - v)² / curvature, the decrease of the objective
  int best_sample = -1;
  const double* residual = residual_.data();
  const double* low_offset = low_offset_.data();
  for_active([&](int sample) {
    const double value = residual[sample] + low_offset[sample];
    smallest_low = std::min(smallest_low, value);
    const double gap = largest_up - value;
    double curvature = 2.0 - 2.0 * first_column[sample];
    curvature = curvature > 0 ? curvature : kTau;
    if (gap > 0 && gap * gap > best_score * curvature) {  // score > best, without a division
      best_score = gap * gap / curvature;
      best_sample = sample;
    }
  });
  *second = best_sample < 0 ? Variable{} : Variable{best_sample, alpha_[best_sample] > 0 ? 0 : 1};
  return largest_up - smallest_low < settings_.tolerance || second->sample < 0;
}

// Solves the two-variable subproblem in (first, second) exactly and updates the residual.
void SvrSmo::take_step(Variable first, Variable second) {
  const double* first_column = cache_.column(first.sample, active_, false);
  const double* second_column = cache_.column(second.sample, active_, false);
  // the second fetch cannot evict the first: the cache holds at least two columns
  double& a_i = value_of(first);
  double& a_j = value_of(second);
  const double old_i = a_i;
  const double old_j = a_j;
  const double y_i = first.sign();
  const double y_j = second.sign();
  const double q_ij = y_i * y_j * first_column[second.sample];
  const double gradient_i = epsilon_ - y_i * residual_[first.sample];
  const double gradient_j = epsilon_ - y_j * residual_[second.sample];
  const double C = C_;

  if (y_i != y_j) {
    double curvature = 2.0 + 2.0 * q_ij;
    if (curvature <= 0) curvature = kTau;
    const double delta = (-gradient_i - gradient_j) / curvature;
    const double difference = a_i - a_j;
    a_i += delta;
    a_j += delta;
    if (difference > 0) {
      if (a_j < 0) { a_j = 0; a_i = difference; }
    } else {
      if (a_i < 0) { a_i = 0; a_j = -difference; }
    }
    if (difference > 0) {  // C_i - C_j = 0
      if (a_i > C) { a_i = C; a_j = C - difference; }
    } else {
      if (a_j > C) { a_j = C; a_i = C + difference; }
    }
  } else {
    double curvature = 2.0 - 2.0 * q_ij;
    if (curvature <= 0) curvature = kTau;
    const double delta = (gradient_i - gradient_j) / curvature;
    const double sum = a_i + a_j;
    a_i -= delta;
    a_j += delta;
    if (sum > C) {
      if (a_i > C) { a_i = C; a_j = sum - C; }
    } else {
      if (a_j < 0) { a_j = 0; a_i = sum; }
    }
    if (sum > C) {
      if (a_j > C) { a_j = C; a_i = sum - C; }
    } else {
      if (a_i < 0) { a_i = 0; a_j = sum; }
    }
  }

  // r -= K Δβ on the active samples, finding the next first variable on the way.
  double change_i = y_i * (a_i - old_i);
  double change_j = y_j * (a_j - old_j);
  if (first.sample == second.sample) {
    change_i += change_j;
    change_j = 0;
  }
  refresh_offsets(first.sample);
  refresh_offsets(second.sample);
  double* residual = residual_.data();
  const double* up_offset = up_offset_.data();
  double best = -kInfinity;
  int best_sample = -1;
  for_active([&](int sample) {
    const double r = residual[sample] - change_i * first_column[sample] - change_j * second_column[sample];
    residual[sample] = r;
    const double value = r + up_offset[sample];
    if (value > best) {
      best = value;
      best_sample = sample;
    }
  });
  const Variable best_variable =
      best_sample < 0 ? Variable{} : Variable{best_sample, alpha_star_[best_sample] > 0 ? 1 : 0};
  first_ = best_variable;
  first_value_ = best;
  first_known_ = true;

  // Keep K β_C current when a variable reaches or leaves C (needs the whole column).
  auto follow_bound = [&](Variable v, double before, double after) {
    const bool was_at_c = before >= C;
    const bool is_at_c = after >= C;
    if (was_at_c == is_at_c) return;
    const double change = (is_at_c ? C : -C) * v.sign();
    const double* column = cache_.column(v.sample, active_, true);
    for (int row = 0; row < size_; ++row) bounded_part_[row] += change * column[row];
  };
  follow_bound(first, old_i, a_i);
  follow_bound(second, old_j, a_j);
}

// Rebuilds r = z - K β_C - K β_free on the samples outside the active set.
void SvrSmo::reconstruct_residual() {
  if (all_active()) return;
  std::vector<char> is_active(size_, 0);
  for (int sample : active_) is_active[sample] = 1;
  std::vector<int> inactive;
  for (int sample = 0; sample < size_; ++sample)
    if (!is_active[sample]) inactive.push_back(sample);
  std::vector<int> free_samples;
  std::vector<double> free_beta;
  for (int sample = 0; sample < size_; ++sample) {
    const double a = alpha_[sample];
    const double a_star = alpha_star_[sample];
    const double beta = (a > 0 && a < C_ ? a : 0.0) - (a_star > 0 && a_star < C_ ? a_star : 0.0);
    if (beta != 0) {
      free_samples.push_back(sample);
      free_beta.push_back(beta);
    }
  }
  auto rebuild = [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const int sample = inactive[k];
      double sum = bounded_part_[sample];
      for (std::size_t f = 0; f < free_samples.size(); ++f)
        sum += free_beta[f] * kernel_(static_cast<std::size_t>(sample), static_cast<std::size_t>(free_samples[f]));
      residual_[sample] = targets_(sample) - sum;
    }
  };
  if (inactive.size() * free_samples.size() > 100'000) {
    pool_.run(inactive.size(), rebuild);
  } else {
    rebuild(0, inactive.size());
  }
}

void SvrSmo::activate_all() {
  if (all_active()) return;
  active_.resize(size_);
  for (int sample = 0; sample < size_; ++sample) active_[sample] = sample;
  cache_.start_epoch();
  first_known_ = false;
}

void SvrSmo::shrink() {
  const auto [largest_up, smallest_low] = violation_bounds(active_);
  if (!unshrunk_ && largest_up - smallest_low <= 10 * settings_.tolerance) {
    // Close to the end: bring every sample back once, so that the final checks see them.
    unshrunk_ = true;
    reconstruct_residual();
    activate_all();
  }
  auto stays = [&](int sample) {
    const double r = residual_[sample];
    const double a = alpha_[sample];
    const double a_star = alpha_star_[sample];
    bool fixed_alpha = false;  // α cannot move in the next steps
    if (a >= C_) fixed_alpha = r - epsilon_ > largest_up;
    else if (a <= 0) fixed_alpha = r - epsilon_ < smallest_low;
    bool fixed_alpha_star = false;
    if (a_star >= C_) fixed_alpha_star = r + epsilon_ < smallest_low;
    else if (a_star <= 0) fixed_alpha_star = r + epsilon_ > largest_up;
    return !(fixed_alpha && fixed_alpha_star);
  };
  std::vector<int> kept;
  kept.reserve(active_.size());
  for (int sample : active_)
    if (stays(sample)) kept.push_back(sample);
  if (kept.size() != active_.size()) {
    active_.swap(kept);
    first_known_ = false;
  }
}

SmoSolution SvrSmo::solve() {
  SmoSolution solution;
  const long variables = 2L * size_;
  long countdown = std::min(variables, 1000L);
  long iterations = 0;
  bool converged = false;
  while (iterations < settings_.max_iterations) {
    if (--countdown == 0) {
      countdown = std::min(variables, 1000L);
      if (settings_.shrinking) shrink();
    }
    Variable first, second;
    if (select_working_set(&first, &second)) {
      reconstruct_residual();
      activate_all();
      if (select_working_set(&first, &second)) {
        converged = true;
        break;
      }
      countdown = 1;  // shrink again at the next step
    }
    ++iterations;
    take_step(first, second);
  }
  if (!converged) {
    reconstruct_residual();
    activate_all();
  }

  std::vector<int> everyone(size_);
  for (int sample = 0; sample < size_; ++sample) everyone[sample] = sample;
  const auto [largest_up, smallest_low] = violation_bounds(everyone);
  solution.max_violation = std::max(0.0, largest_up - smallest_low);
  // An exact zero of the loop's test can also end a capped run.
  solution.converged = converged || solution.max_violation < settings_.tolerance;
  solution.iterations = iterations;

  // ρ as libsvm: the mean of y G over free variables, else the middle of the bounds.
  double upper = kInfinity, lower = -kInfinity, free_sum = 0;
  long free_count = 0;
  double twice_objective = 0;
  for (int sample = 0; sample < size_; ++sample) {
    const double r = residual_[sample];
    const double z = targets_(sample);
    const double a = alpha_[sample];
    const double a_star = alpha_star_[sample];
    const double y_gradient = epsilon_ - r;         // α:  y = +1, G = ε - r
    const double y_gradient_star = -epsilon_ - r;  // α*: y = -1, G = ε + r
    if (a >= C_) lower = std::max(lower, y_gradient);
    else if (a <= 0) upper = std::min(upper, y_gradient);
    else { ++free_count; free_sum += y_gradient; }
    if (a_star >= C_) upper = std::min(upper, y_gradient_star);
    else if (a_star <= 0) lower = std::max(lower, y_gradient_star);
    else { ++free_count; free_sum += y_gradient_star; }
    // a_t (G_t + p_t)
    twice_objective += a * (2 * epsilon_ - r - z) + a_star * (2 * epsilon_ + r + z);
  }
  solution.rho = free_count > 0 ? free_sum / static_cast<double>(free_count) : (upper + lower) / 2;
  solution.objective = twice_objective / 2;
  solution.alpha = Eigen::Map<const Eigen::VectorXd>(alpha_.data(), size_);
  solution.alpha_star = Eigen::Map<const Eigen::VectorXd>(alpha_star_.data(), size_);
  return solution;
}

}  // namespace

SmoSolution solve_svr_dual(const Eigen::VectorXd& targets, const SmoSettings& settings,
                           const RbfKernel& kernel, KernelCache& cache, WorkerPool& pool,
                           const Eigen::VectorXd* alpha, const Eigen::VectorXd* alpha_star) {
  SvrSmo smo(targets, settings, kernel, cache, pool);
  if (alpha && alpha_star) {
    smo.start_from(*alpha, *alpha_star);
  } else {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(targets.size());
    smo.start_from(zero, zero);
  }
  return smo.solve();
}

}  // namespace thermodrift::svr_detail
