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
//
// Layout: every per-sample array is indexed by *position*, with the active samples at
// positions [0, active) (shrinking swaps a dropped sample to the end, as libsvm's
// swap_index), so the two per-step sweeps (residual update with the argmax for the next
// i; selection of j) run over contiguous arrays. They are written with GCC vector types
// and compiled twice (AVX2 and baseline x86-64, chosen at load time by target_clones).
#include "svr_solver.hpp"

#include "svr_simd.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

namespace thermodrift::svr_detail {

namespace {

constexpr double kTau = 1e-12;  // curvature used when K_ii + K_jj - 2K_ij ≤ 0
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------- sweeps

using simd::Lanes;
using simd::LaneMask;
using simd::kLanes;
using simd::load;
using simd::store;

struct Argmax {
  double value = -kInfinity;
  int position = -1;
};

// Both sweeps keep several independent sets of per-lane bests, so that consecutive
// vectors do not wait on one compare-and-select chain (at n = 2271 the single-chain
// loops were latency-bound). The sets cover interleaved positions; the final reduction
// takes the best over all lanes and the first position on ties, as a scalar scan.
constexpr int kArgmaxSets = 4;
constexpr int kSelectionSets = 2;

// r_p -= change_i K_pi + change_j K_pj on [0, count); returns argmax_p r_p + up_offset_p.
THERMODRIFT_SIMD_CLONES
Argmax update_residual(double* residual, const double* up_offset, const double* column_i, const double* column_j,
                       double change_i, double change_j, int count) {
  constexpr int kBlock = kLanes * kArgmaxSets;
  Lanes best[kArgmaxSets];
  LaneMask best_position[kArgmaxSets];
  for (int set = 0; set < kArgmaxSets; ++set) {
    best[set] = Lanes{-kInfinity, -kInfinity, -kInfinity, -kInfinity};
    best_position[set] = LaneMask{-1, -1, -1, -1};
  }
  LaneMask position = {0, 1, 2, 3};
  int p = 0;
  for (; p + kBlock <= count; p += kBlock) {
    for (int set = 0; set < kArgmaxSets; ++set) {
      const int at = p + set * kLanes;
      const Lanes r = load(residual + at) - change_i * load(column_i + at) - change_j * load(column_j + at);
      store(residual + at, r);
      const Lanes value = r + load(up_offset + at);
      const LaneMask better = value > best[set];
      best[set] = better ? value : best[set];
      best_position[set] = better ? position + set * kLanes : best_position[set];
    }
    position += kBlock;
  }
  Argmax result;
  for (int set = 0; set < kArgmaxSets; ++set) {
    for (int lane = 0; lane < kLanes; ++lane) {
      const int at = static_cast<int>(best_position[set][lane]);
      const double value = best[set][lane];
      if (at >= 0 && (value > result.value || (value == result.value && at < result.position))) {
        result.value = value;
        result.position = at;
      }
    }
  }
  for (; p < count; ++p) {
    const double r = residual[p] - change_i * column_i[p] - change_j * column_j[p];
    residual[p] = r;
    const double value = r + up_offset[p];
    if (value > result.value) {
      result.value = value;
      result.position = p;
    }
  }
  return result;
}

struct SecondChoice {
  int position = -1;
  double smallest_low = kInfinity;  // M(a)
};

// Second-order choice of j for a given m(a) = largest_up and the column of i: maximises
// (m - v_p)² / (2 - 2 K_pi) over v_p = r_p + low_offset_p < m; also returns min_p v_p.
// Scores are compared as cross products (gap² · curvature' > gap'² · curvature).
THERMODRIFT_SIMD_CLONES
SecondChoice select_second(const double* residual, const double* low_offset, const double* column_i,
                           double largest_up, int count) {
  constexpr int kBlock = kLanes * kSelectionSets;
  Lanes smallest[kSelectionSets];
  Lanes best_gain[kSelectionSets];       // gap², per lane
  Lanes best_curvature[kSelectionSets];  // its curvature
  LaneMask best_position[kSelectionSets];
  for (int set = 0; set < kSelectionSets; ++set) {
    smallest[set] = Lanes{kInfinity, kInfinity, kInfinity, kInfinity};
    best_gain[set] = Lanes{0, 0, 0, 0};
    best_curvature[set] = Lanes{1, 1, 1, 1};
    best_position[set] = LaneMask{-1, -1, -1, -1};
  }
  LaneMask position = {0, 1, 2, 3};
  const Lanes tau = {kTau, kTau, kTau, kTau};
  const Lanes zero = {0, 0, 0, 0};
  int p = 0;
  for (; p + kBlock <= count; p += kBlock) {
    for (int set = 0; set < kSelectionSets; ++set) {
      const int at = p + set * kLanes;
      const Lanes value = load(residual + at) + load(low_offset + at);
      smallest[set] = value < smallest[set] ? value : smallest[set];
      const Lanes gap = largest_up - value;
      Lanes curvature = 2.0 - 2.0 * load(column_i + at);
      curvature = curvature > zero ? curvature : tau;
      const Lanes gain = gap * gap;
      const LaneMask better = (gap > zero) & (gain * best_curvature[set] > best_gain[set] * curvature);
      best_gain[set] = better ? gain : best_gain[set];
      best_curvature[set] = better ? curvature : best_curvature[set];
      best_position[set] = better ? position + set * kLanes : best_position[set];
    }
    position += kBlock;
  }
  SecondChoice result;
  double gain = 0, curvature_of_best = 1;
  for (int set = 0; set < kSelectionSets; ++set) {
    for (int lane = 0; lane < kLanes; ++lane) {
      result.smallest_low = std::min(result.smallest_low, smallest[set][lane]);
      const int at = static_cast<int>(best_position[set][lane]);
      if (at < 0) continue;
      const double left = best_gain[set][lane] * curvature_of_best, right = gain * best_curvature[set][lane];
      if (left > right || (left == right && (result.position < 0 || at < result.position))) {
        gain = best_gain[set][lane];
        curvature_of_best = best_curvature[set][lane];
        result.position = at;
      }
    }
  }
  for (; p < count; ++p) {
    const double value = residual[p] + low_offset[p];
    result.smallest_low = std::min(result.smallest_low, value);
    const double gap = largest_up - value;
    double curvature = 2.0 - 2.0 * column_i[p];
    curvature = curvature > 0 ? curvature : kTau;
    if (gap > 0 && gap * gap * curvature_of_best > gain * curvature) {
      gain = gap * gap;
      curvature_of_best = curvature;
      result.position = p;
    }
  }
  return result;
}

// ---------------------------------------------------------------------------- solver

// One of the 2n variables: half 0 is α (y = +1), half 1 is α* (y = -1) of the sample
// at `position`.
struct Variable {
  int position = -1;
  int half = 0;
  double sign() const { return half == 0 ? 1.0 : -1.0; }
};

class SvrSmo {
 public:
  SvrSmo(const Eigen::VectorXd& targets, const SmoSettings& settings, RbfKernel& kernel, KernelCache& cache,
         WorkerPool& pool)
      : size_(static_cast<int>(targets.size())),
        C_(settings.C),
        epsilon_(settings.epsilon),
        settings_(settings),
        kernel_(kernel),
        cache_(cache),
        pool_(pool),
        target_(size_),
        alpha_(size_, 0.0),
        alpha_star_(size_, 0.0),
        residual_(size_),
        bounded_part_(size_, 0.0),
        up_offset_(size_),
        low_offset_(size_),
        active_size_(size_) {
    for (int position = 0; position < size_; ++position) target_[position] = targets(kernel_.sample_at(position));
  }

  void start_from(const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star);
  SmoSolution solve();

 private:
  void refresh_offsets(int position) {
    const double a = alpha_[position], a_star = alpha_star_[position];
    up_offset_[position] = a_star > 0 ? epsilon_ : (a < C_ ? -epsilon_ : -kInfinity);
    low_offset_[position] = a > 0 ? -epsilon_ : (a_star < C_ ? epsilon_ : kInfinity);
  }
  double& value_of(Variable v) { return v.half == 0 ? alpha_[v.position] : alpha_star_[v.position]; }
  bool all_active() const { return active_size_ == size_; }
  void find_first();
  bool select_working_set(Variable* first, Variable* second);
  void take_step(Variable first, Variable second);
  void shrink();
  void swap_positions(int a, int b);
  void reconstruct_residual();
  void activate_all();
  std::pair<double, double> violation_bounds(int count) const;

  int size_;
  double C_;
  double epsilon_;
  SmoSettings settings_;
  RbfKernel& kernel_;
  KernelCache& cache_;
  WorkerPool& pool_;

  // All per position (kernel_.sample_at(position) is the sample).
  std::vector<double> target_;
  std::vector<double> alpha_;
  std::vector<double> alpha_star_;
  std::vector<double> residual_;      // z - Kβ, up to date on active positions
  std::vector<double> bounded_part_;  // K β_C, β_C = C·[α = C] - C·[α* = C], on all positions
  // Per position, the offset of its best I_up candidate from r (max over its two halves
  // of -y G - r: +ε if α* > 0, else -ε if α < C, else -∞) and of its best I_low candidate
  // (min of -y G - r: -ε if α > 0, else +ε if α* < C, else +∞). The sweeps read one
  // number per sample instead of testing both halves.
  std::vector<double> up_offset_;
  std::vector<double> low_offset_;
  int active_size_;                   // active samples sit at positions [0, active_size_)
  bool unshrunk_ = false;

  // The first variable of the next working set, found while updating the residual.
  Variable first_;
  double first_value_ = -kInfinity;
  bool first_known_ = false;
};

void SvrSmo::start_from(const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star) {
  for (int position = 0; position < size_; ++position) {
    const int sample = kernel_.sample_at(position);
    alpha_[position] = alpha(sample);
    alpha_star_[position] = alpha_star(sample);
    refresh_offsets(position);
    residual_[position] = target_[position];
  }
  for (int position = 0; position < size_; ++position) {
    const double beta = alpha_[position] - alpha_star_[position];
    const double bounded = (alpha_[position] >= C_ ? C_ : 0.0) - (alpha_star_[position] >= C_ ? C_ : 0.0);
    if (beta == 0 && bounded == 0) continue;
    const double* column = cache_.column(position, size_);
    for (int row = 0; row < size_; ++row) {
      residual_[row] -= beta * column[row];
      bounded_part_[row] += bounded * column[row];
    }
  }
}

// m(a) = max over I_up of -y G, and M(a) = min over I_low of -y G, over positions [0, count).
std::pair<double, double> SvrSmo::violation_bounds(int count) const {
  double largest_up = -kInfinity;
  double smallest_low = kInfinity;
  for (int position = 0; position < count; ++position) {
    const double r = residual_[position];
    largest_up = std::max(largest_up, r + up_offset_[position]);
    smallest_low = std::min(smallest_low, r + low_offset_[position]);
  }
  return {largest_up, smallest_low};
}

void SvrSmo::find_first() {
  double best = -kInfinity;
  int best_position = -1;
  for (int position = 0; position < active_size_; ++position) {
    const double value = residual_[position] + up_offset_[position];
    if (value > best) {
      best = value;
      best_position = position;
    }
  }
  first_value_ = best;
  first_ = best_position < 0 ? Variable{} : Variable{best_position, alpha_star_[best_position] > 0 ? 1 : 0};
  first_known_ = true;
}

// Returns true when the active problem is optimal within the tolerance.
bool SvrSmo::select_working_set(Variable* first, Variable* second) {
  if (!first_known_) find_first();
  const double largest_up = first_value_;  // m(a)
  *first = first_;
  if (first_.position < 0) return true;
  const double* first_column = cache_.column(first_.position, active_size_);
  // For each sample only its I_low half with the smaller -y G can win: both share the
  // curvature K_ii + K_jj - 2 K_ij = 2 - 2 K_ij (K_ii = 1) and the larger gap wins.
  const SecondChoice choice =
      select_second(residual_.data(), low_offset_.data(), first_column, largest_up, active_size_);
  *second = choice.position < 0 ? Variable{} : Variable{choice.position, alpha_[choice.position] > 0 ? 0 : 1};
  return largest_up - choice.smallest_low < settings_.tolerance || second->position < 0;
}

// Solves the two-variable subproblem in (first, second) exactly and updates the residual.
void SvrSmo::take_step(Variable first, Variable second) {
  const double* first_column = cache_.column(first.position, active_size_);
  const double* second_column = cache_.column(second.position, active_size_);
  // the second fetch cannot evict the first: the cache holds at least two columns
  double& a_i = value_of(first);
  double& a_j = value_of(second);
  const double old_i = a_i;
  const double old_j = a_j;
  const double y_i = first.sign();
  const double y_j = second.sign();
  const double q_ij = y_i * y_j * first_column[second.position];
  const double gradient_i = epsilon_ - y_i * residual_[first.position];
  const double gradient_j = epsilon_ - y_j * residual_[second.position];
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

  // r -= K Δβ on the active positions, finding the next first variable on the way.
  double change_i = y_i * (a_i - old_i);
  double change_j = y_j * (a_j - old_j);
  if (first.position == second.position) {
    change_i += change_j;
    change_j = 0;
  }
  refresh_offsets(first.position);
  refresh_offsets(second.position);
  const Argmax best = update_residual(residual_.data(), up_offset_.data(), first_column, second_column, change_i,
                                      change_j, active_size_);
  first_ = best.position < 0 ? Variable{} : Variable{best.position, alpha_star_[best.position] > 0 ? 1 : 0};
  first_value_ = best.value;
  first_known_ = true;

  // Keep K β_C current when a variable reaches or leaves C (needs the whole column).
  auto follow_bound = [&](Variable v, double before, double after) {
    const bool was_at_c = before >= C;
    const bool is_at_c = after >= C;
    if (was_at_c == is_at_c) return;
    const double change = (is_at_c ? C : -C) * v.sign();
    const double* column = cache_.column(v.position, size_);
    double* bounded_part = bounded_part_.data();
    for (int row = 0; row < size_; ++row) bounded_part[row] += change * column[row];
  };
  follow_bound(first, old_i, a_i);
  follow_bound(second, old_j, a_j);
}

// Rebuilds r = z - K β_C - K β_free on the positions outside the active set.
void SvrSmo::reconstruct_residual() {
  if (all_active()) return;
  std::vector<int> free_positions;
  std::vector<double> free_beta;
  for (int position = 0; position < size_; ++position) {
    const double a = alpha_[position];
    const double a_star = alpha_star_[position];
    const double beta = (a > 0 && a < C_ ? a : 0.0) - (a_star > 0 && a_star < C_ ? a_star : 0.0);
    if (beta != 0) {
      free_positions.push_back(position);
      free_beta.push_back(beta);
    }
  }
  const auto first_inactive = static_cast<std::size_t>(active_size_);
  const std::size_t inactive = static_cast<std::size_t>(size_) - first_inactive;
  // Each thread takes a range of inactive positions and walks the free variables with
  // one vectorised kernel evaluation per (free variable, range).
  auto rebuild = [&](std::size_t begin, std::size_t end) {
    begin += first_inactive;
    end += first_inactive;
    std::vector<double> column(static_cast<std::size_t>(size_));
    std::vector<double> sum(bounded_part_.begin() + static_cast<std::ptrdiff_t>(begin),
                            bounded_part_.begin() + static_cast<std::ptrdiff_t>(end));
    for (std::size_t f = 0; f < free_positions.size(); ++f) {
      kernel_.column_serial(static_cast<std::size_t>(free_positions[f]), begin, end, column.data());
      const double beta = free_beta[f];
      for (std::size_t position = begin; position < end; ++position) sum[position - begin] += beta * column[position];
    }
    for (std::size_t position = begin; position < end; ++position)
      residual_[position] = target_[position] - sum[position - begin];
  };
  if (inactive * free_positions.size() > 100'000) {
    pool_.run(inactive, rebuild);
  } else {
    rebuild(0, inactive);
  }
}

void SvrSmo::activate_all() {
  if (all_active()) return;
  active_size_ = size_;
  first_known_ = false;
}

void SvrSmo::swap_positions(int a, int b) {
  std::swap(target_[a], target_[b]);
  std::swap(alpha_[a], alpha_[b]);
  std::swap(alpha_star_[a], alpha_star_[b]);
  std::swap(residual_[a], residual_[b]);
  std::swap(bounded_part_[a], bounded_part_[b]);
  std::swap(up_offset_[a], up_offset_[b]);
  std::swap(low_offset_[a], low_offset_[b]);
}

void SvrSmo::shrink() {
  // Plain copies, not structured bindings: C++20 lambdas may not capture bindings in clang 14.
  const auto bounds = violation_bounds(active_size_);
  const double largest_up = bounds.first;
  const double smallest_low = bounds.second;
  if (!unshrunk_ && largest_up - smallest_low <= 10 * settings_.tolerance) {
    // Close to the end: bring every sample back once, so that the final checks see them.
    unshrunk_ = true;
    reconstruct_residual();
    activate_all();
  }
  auto stays = [&](int position) {
    const double r = residual_[position];
    const double a = alpha_[position];
    const double a_star = alpha_star_[position];
    bool fixed_alpha = false;  // α cannot move in the next steps
    if (a >= C_) fixed_alpha = r - epsilon_ > largest_up;
    else if (a <= 0) fixed_alpha = r - epsilon_ < smallest_low;
    bool fixed_alpha_star = false;
    if (a_star >= C_) fixed_alpha_star = r + epsilon_ < smallest_low;
    else if (a_star <= 0) fixed_alpha_star = r + epsilon_ > largest_up;
    return !(fixed_alpha && fixed_alpha_star);
  };
  // Dropped samples go to the end: each is exchanged with the last staying one.
  std::vector<std::pair<int, int>> exchanges;
  int end = active_size_;
  int position = 0;
  while (position < end) {
    if (stays(position)) {
      ++position;
      continue;
    }
    --end;
    while (end > position && !stays(end)) --end;
    if (end > position) {
      swap_positions(position, end);
      exchanges.emplace_back(position, end);
      ++position;
    }
  }
  cache_.swap(exchanges);
  if (end != active_size_) {
    active_size_ = end;
    first_known_ = false;
  }
}

SmoSolution SvrSmo::solve() {
  settings_.stop.throw_if_requested("SVR fit");
  SmoSolution solution;
  const long variables = 2L * size_;
  long countdown = std::min(variables, 1000L);
  long iterations = 0;
  bool converged = false;
  while (iterations < settings_.max_iterations) {
    if (--countdown == 0) {
      countdown = std::min(variables, 1000L);
      settings_.stop.throw_if_requested("SVR fit");
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

  const auto [largest_up, smallest_low] = violation_bounds(size_);
  solution.max_violation = std::max(0.0, largest_up - smallest_low);
  // An exact zero of the loop's test can also end a capped run.
  solution.converged = converged || solution.max_violation < settings_.tolerance;
  solution.iterations = iterations;

  // ρ as libsvm: the mean of y G over free variables, else the middle of the bounds.
  double upper = kInfinity, lower = -kInfinity, free_sum = 0;
  long free_count = 0;
  double twice_objective = 0;
  solution.alpha.resize(size_);
  solution.alpha_star.resize(size_);
  for (int position = 0; position < size_; ++position) {
    const double r = residual_[position];
    const double z = target_[position];
    const double a = alpha_[position];
    const double a_star = alpha_star_[position];
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
    const int sample = kernel_.sample_at(position);
    solution.alpha(sample) = a;
    solution.alpha_star(sample) = a_star;
  }
  solution.rho = free_count > 0 ? free_sum / static_cast<double>(free_count) : (upper + lower) / 2;
  solution.objective = twice_objective / 2;
  return solution;
}

}  // namespace

SmoSolution solve_svr_dual(const Eigen::VectorXd& targets, const SmoSettings& settings,
                           RbfKernel& kernel, KernelCache& cache, WorkerPool& pool,
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
