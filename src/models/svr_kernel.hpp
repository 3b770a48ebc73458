// Internal to the ε-SVR solver: a small pool of worker threads, the RBF kernel over an
// SvrDataset, and the LRU cache of kernel columns with a byte budget.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
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

// K(a, b) = exp(-gamma ||x_a - x_b||²) over the samples of a data set.
class RbfKernel {
 public:
  RbfKernel(const SvrDataset& data, double gamma, WorkerPool& pool);

  std::size_t size() const { return size_; }
  double operator()(std::size_t a, std::size_t b) const;
  // out[r] = K(r, column) for every r in `rows`, or for all r when rows is null.
  void column(std::size_t column, const std::vector<int>* rows, double* out) const;

 private:
  void column_range(std::size_t column, const std::vector<int>* rows, std::size_t begin,
                    std::size_t end, double* out) const;

  const SvrDataset& data_;
  double gamma_;
  std::size_t size_;
  WorkerPool& pool_;
};

// Columns of the kernel matrix, least recently used evicted first, within a byte
// budget (at least two columns: the solver holds the pair of its working set).
// A column may be computed only on the active rows; such a column stays valid until
// the active set grows again (a new "epoch"), as shrinking only removes rows.
class KernelCache {
 public:
  KernelCache(const RbfKernel& kernel, double budget_mb);

  // Column `column`, valid on every row in `active` (on all rows if `full`).
  const double* column(int column, const std::vector<int>& active, bool full);
  void start_epoch() { ++epoch_; }
  std::size_t columns_computed() const { return columns_computed_; }
  std::size_t capacity() const { return capacity_; }

 private:
  void touch(int column);  // move to the most-recently-used end
  void unlink(int column);

  const RbfKernel& kernel_;
  std::size_t size_;
  std::size_t capacity_;                        // columns that fit the budget
  std::vector<std::unique_ptr<double[]>> slots_;
  std::vector<int> slot_of_;                    // per column: slot or -1
  std::vector<int> column_of_slot_;
  std::vector<long> epoch_of_;                  // per column: epoch when computed partially, -1 when full
  std::vector<int> previous_, next_;            // LRU list over columns; sentinel = size_
  long epoch_ = 0;
  std::size_t columns_computed_ = 0;
};

}  // namespace thermodrift::svr_detail
