#include "svr_kernel.hpp"

#include <algorithm>
#include <cmath>

namespace thermodrift::svr_detail {

// ---------------------------------------------------------------------------- pool

WorkerPool::WorkerPool(int threads) {
  for (int index = 1; index < threads; ++index) workers_.emplace_back([this, index] { work(index); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  job_posted_.notify_all();
  for (auto& worker : workers_) worker.join();
}

namespace {
std::pair<std::size_t, std::size_t> share(std::size_t count, int parts, int index) {
  const std::size_t begin = count * static_cast<std::size_t>(index) / static_cast<std::size_t>(parts);
  const std::size_t end = count * static_cast<std::size_t>(index + 1) / static_cast<std::size_t>(parts);
  return {begin, end};
}
}  // namespace

void WorkerPool::run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& job) {
  if (workers_.empty() || count < 2) {
    job(0, count);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    job_ = &job;
    count_ = count;
    pending_ = static_cast<int>(workers_.size());
    ++generation_;
  }
  job_posted_.notify_all();
  auto [begin, end] = share(count, threads(), 0);
  job(begin, end);
  std::unique_lock lock(mutex_);
  job_done_.wait(lock, [this] { return pending_ == 0; });
  job_ = nullptr;
}

void WorkerPool::work(int worker_index) {
  long seen = 0;
  for (;;) {
    const std::function<void(std::size_t, std::size_t)>* job = nullptr;
    std::size_t count = 0;
    {
      std::unique_lock lock(mutex_);
      job_posted_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      job = job_;
      count = count_;
    }
    auto [begin, end] = share(count, threads(), worker_index);
    (*job)(begin, end);
    {
      std::lock_guard lock(mutex_);
      --pending_;
    }
    job_done_.notify_one();
  }
}

// ---------------------------------------------------------------------------- kernel

namespace {
// Below this many entries a column is computed on one thread: waking a worker costs
// more than it saves (measured in bench/svr_bench.cpp).
constexpr std::size_t kParallelColumnLength = 8192;
}  // namespace

RbfKernel::RbfKernel(const SvrDataset& data, double gamma, WorkerPool& pool)
    : data_(data), gamma_(gamma), size_(data.size()), pool_(pool) {}

double RbfKernel::operator()(std::size_t a, std::size_t b) const {
  if (data_.has_distances()) {
    return std::exp(-gamma_ * data_.squared_distances()(static_cast<Eigen::Index>(a),
                                                        static_cast<Eigen::Index>(b)));
  }
  const Eigen::MatrixXd& x = data_.samples();
  const auto ra = static_cast<Eigen::Index>(a);
  const auto rb = static_cast<Eigen::Index>(b);
  double squared = 0;
  for (Eigen::Index feature = 0; feature < x.cols(); ++feature) {
    const double difference = x(ra, feature) - x(rb, feature);
    squared += difference * difference;
  }
  return std::exp(-gamma_ * squared);
}

void RbfKernel::column(std::size_t column, const std::vector<int>* rows, double* out) const {
  const std::size_t count = rows ? rows->size() : size_;
  if (pool_.threads() > 1 && count >= kParallelColumnLength) {
    pool_.run(count, [&](std::size_t begin, std::size_t end) {
      column_range(column, rows, begin, end, out);
    });
  } else {
    column_range(column, rows, 0, count, out);
  }
}

// Rows [begin, end) of `rows` (or of all rows) of one column.
void RbfKernel::column_range(std::size_t column, const std::vector<int>* rows, std::size_t begin,
                             std::size_t end, double* out) const {
  const double gamma = gamma_;
  if (data_.has_distances()) {
    const double* distances = data_.squared_distances().col(static_cast<Eigen::Index>(column)).data();
    if (rows) {
      for (std::size_t k = begin; k < end; ++k) {
        const int row = (*rows)[k];
        out[row] = std::exp(-gamma * distances[row]);
      }
    } else {
      for (std::size_t row = begin; row < end; ++row) out[row] = std::exp(-gamma * distances[row]);
    }
    return;
  }
  const Eigen::MatrixXd& x = data_.samples();
  const auto features = x.cols();
  const auto center = static_cast<Eigen::Index>(column);
  if (rows) {
    for (std::size_t k = begin; k < end; ++k) {
      const Eigen::Index row = (*rows)[k];
      double squared = 0;
      for (Eigen::Index feature = 0; feature < features; ++feature) {
        const double difference = x(row, feature) - x(center, feature);
        squared += difference * difference;
      }
      out[row] = std::exp(-gamma * squared);
    }
    return;
  }
  // Column-major samples: one pass per feature over contiguous memory.
  for (std::size_t row = begin; row < end; ++row) out[row] = 0;
  for (Eigen::Index feature = 0; feature < features; ++feature) {
    const double* values = x.col(feature).data();
    const double reference = values[center];
    for (std::size_t row = begin; row < end; ++row) {
      const double difference = values[row] - reference;
      out[row] += difference * difference;
    }
  }
  for (std::size_t row = begin; row < end; ++row) out[row] = std::exp(-gamma * out[row]);
}

// ---------------------------------------------------------------------------- cache

KernelCache::KernelCache(const RbfKernel& kernel, double budget_mb)
    : kernel_(kernel),
      size_(kernel.size()),
      slot_of_(kernel.size(), -1),
      epoch_of_(kernel.size(), 0),
      previous_(kernel.size() + 1),
      next_(kernel.size() + 1) {
  const double column_bytes = static_cast<double>(std::max<std::size_t>(size_, 1)) * sizeof(double);
  const double fitting = budget_mb * 1024.0 * 1024.0 / column_bytes;
  capacity_ = static_cast<std::size_t>(std::clamp(fitting, 2.0, static_cast<double>(std::max<std::size_t>(size_, 2))));
  const int sentinel = static_cast<int>(size_);
  previous_[size_] = sentinel;
  next_[size_] = sentinel;
}

void KernelCache::unlink(int column) {
  next_[previous_[column]] = next_[column];
  previous_[next_[column]] = previous_[column];
}

void KernelCache::touch(int column) {
  const int sentinel = static_cast<int>(size_);
  // most recently used sits just before the sentinel
  previous_[column] = previous_[sentinel];
  next_[column] = sentinel;
  next_[previous_[sentinel]] = column;
  previous_[sentinel] = column;
}

const double* KernelCache::column(int column, const std::vector<int>& active, bool full) {
  const bool all_active = active.size() == size_;
  int slot = slot_of_[column];
  if (slot >= 0) {
    unlink(column);
    touch(column);
    const bool valid = epoch_of_[column] < 0 || (!full && epoch_of_[column] == epoch_);
    if (valid) return slots_[slot].get();
  } else {
    if (slots_.size() < capacity_) {
      slot = static_cast<int>(slots_.size());
      slots_.push_back(std::make_unique<double[]>(size_));
      column_of_slot_.push_back(-1);
    } else {
      const int evicted = next_[size_];  // least recently used
      slot = slot_of_[evicted];
      unlink(evicted);
      slot_of_[evicted] = -1;
    }
    slot_of_[column] = slot;
    column_of_slot_[slot] = column;
    touch(column);
  }
  double* data = slots_[slot].get();
  if (full || all_active) {
    kernel_.column(static_cast<std::size_t>(column), nullptr, data);
    epoch_of_[column] = -1;
  } else {
    kernel_.column(static_cast<std::size_t>(column), &active, data);
    epoch_of_[column] = epoch_;
  }
  ++columns_computed_;
  return data;
}

}  // namespace thermodrift::svr_detail
