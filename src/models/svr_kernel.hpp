// Internal to the ε-SVR solver: a small pool of worker threads, the RBF kernel over an
// SvrDataset in the solver's permuted order, and the LRU cache of kernel columns with a
// byte budget.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "thermodrift/models/svr.hpp"

namespace thermodrift::svr_detail {

// Runs one job split into contiguous ranges over a fixed set of threads; the calling
// thread takes the first range. Threads live as long as the pool (one fit).
class WorkerPool {
 public:
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  // Calls job(begin, end) on disjoint ranges covering [0, count); returns when all are done.
  void run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& job);

 private:
  void work(int worker_index);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable job_posted_;
  std::condition_variable job_done_;
  const std::function<void(std::size_t, std::size_t)>* job_ = nullptr;
  std::size_t count_ = 0;
  long generation_ = 0;
  int pending_ = 0;
  bool stopping_ = false;
};

// Σ_k coefficients[k]·exp(-gamma ||v_k - x||²) over `count` vectors stored feature-major
// (columns[f][k], as a column-major Eigen matrix holds them): the RBF sum of a decision
// function, four vectors at a time with the solver's lane-wise exp (≤ 2.3e-16 relative to
// libm's), the products summed in four lanes, then the lanes.
double rbf_sum(const double* const* columns, std::size_t feature_count, const double* x, double gamma,
               const double* coefficients, std::size_t count);

// The same sum with the widest arithmetic this CPU has: eight lanes with fused
// multiply-adds and a table-driven exp on AVX-512, four lanes with fused multiply-adds on
// AVX2, else rbf_sum itself. Within a few 1e-17 of Σ|coefficients| of the formula, like
// rbf_sum, but its last bits depend on the CPU, so only the field's prediction (one
// sample at a time: the Compensator, `compensate`) uses it, never a fit.
double rbf_sum_fast(const double* const* columns, std::size_t feature_count, const double* x, double gamma,
                    const double* coefficients, std::size_t count);

using RbfSumFunction = double (*)(const double* const*, std::size_t, const double*, double, const double*,
                                  std::size_t);
struct RbfSumVariant {
  const char* name;
  RbfSumFunction sum;
};
// The variants this CPU can run, the one rbf_sum_fast takes first; "exact" (rbf_sum) last.
std::vector<RbfSumVariant> rbf_sum_variants();
const char* rbf_sum_fast_arithmetic();  // the name of the one rbf_sum_fast runs

// K(a, b) = exp(-gamma ||x_a - x_b||²) over the samples of a data set, addressed by
// *position*: the solver keeps its active samples at positions [0, active) (as libsvm's
// swap_index) so that its per-step loops run over plain arrays. The kernel keeps the
// samples feature-major in position order; swap() moves two samples.
class RbfKernel {
 public:
  RbfKernel(const SvrDataset& data, double gamma, WorkerPool& pool);

  std::size_t size() const { return size_; }
  int sample_at(std::size_t position) const { return order_[position]; }
  // out[p] = K(p, center) for p in [begin, end) (positions), on `pool` when long.
  void column(std::size_t center, std::size_t begin, std::size_t end, double* out) const;
  // The same on the calling thread only.
  void column_serial(std::size_t center, std::size_t begin, std::size_t end, double* out) const;
  void swap(std::size_t position_a, std::size_t position_b);

 private:

  const SvrDataset& data_;
  double gamma_;
  std::size_t size_;
  WorkerPool& pool_;
  std::vector<int> order_;                   // sample at each position
  std::vector<std::vector<double>> features_;  // features_[f][p]: feature f of the sample at p
};

// Columns of the kernel matrix, least recently used evicted first, within a byte
// budget (at least two columns: the solver holds the pair of its working set). A column
// belongs to a sample; its entries are in position order and valid on [0, length). A
// request for a longer prefix computes only the missing entries (after unshrinking).
class KernelCache {
 public:
  KernelCache(RbfKernel& kernel, double budget_mb);

  // Column of the sample at `position`, valid on positions [0, length).
  const double* column(int position, int length);
  // Exchanges positions a and b in the kernel and (lazily, when next used) in every
  // cached column.
  void swap(const std::vector<std::pair<int, int>>& position_pairs);
  std::size_t columns_computed() const { return columns_computed_; }
  std::size_t capacity() const { return capacity_; }

 private:
  void touch(int sample);  // move to the most-recently-used end
  void unlink(int sample);
  void catch_up(int slot);  // apply the exchanges logged since the slot was last used

  RbfKernel& kernel_;
  std::size_t size_;
  std::size_t capacity_;                        // columns that fit the budget
  std::vector<std::unique_ptr<double[]>> slots_;
  std::vector<int> slot_of_;                    // per sample: slot or -1
  std::vector<int> length_of_slot_;             // valid prefix of each slot
  std::vector<std::size_t> log_position_of_slot_;  // swap_log_ entries already applied
  std::vector<std::pair<int, int>> swap_log_;       // every exchange, (lower, higher) position
  std::vector<int> previous_, next_;            // LRU list over samples; sentinel = size_
  std::size_t columns_computed_ = 0;
};

}  // namespace thermodrift::svr_detail
