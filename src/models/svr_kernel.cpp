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
    : data_(data), gamma_(gamma), size_(data.size()), pool_(pool), order_(data.size()) {
  for (std::size_t position = 0; position < size_; ++position) order_[position] = static_cast<int>(position);
  const Eigen::MatrixXd& x = data.samples();
  features_.resize(static_cast<std::size_t>(x.cols()));
  for (Eigen::Index feature = 0; feature < x.cols(); ++feature)
    features_[static_cast<std::size_t>(feature)].assign(x.col(feature).data(), x.col(feature).data() + size_);
}

void RbfKernel::swap(std::size_t position_a, std::size_t position_b) {
  std::swap(order_[position_a], order_[position_b]);
  for (auto& values : features_) std::swap(values[position_a], values[position_b]);
}

void RbfKernel::column(std::size_t center, std::size_t begin, std::size_t end, double* out) const {
  if (end <= begin) return;
  const std::size_t count = end - begin;
  if (pool_.threads() > 1 && count >= kParallelColumnLength) {
    pool_.run(count, [&](std::size_t from, std::size_t to) { column_serial(center, begin + from, begin + to, out); });
  } else {
    column_serial(center, begin, end, out);
  }
}

// Positions [begin, end) of one column: squared distances feature by feature over
// contiguous memory, then Eigen's vectorised exp. The exp runs on a scratch array padded
// to whole packets, so that every entry takes the packet path: an entry's value must not
// depend on the range it was computed in (a column may be computed in pieces).
void RbfKernel::column_serial(std::size_t center, std::size_t begin, std::size_t end, double* out) const {
  if (end <= begin) return;
  constexpr Eigen::Index kPad = 8;
  const auto count = static_cast<Eigen::Index>(end - begin);
  Eigen::ArrayXd scratch = Eigen::ArrayXd::Zero((count + kPad - 1) / kPad * kPad);
  if (data_.has_distances()) {
    const double* distances = data_.squared_distances().col(order_[center]).data();
    for (Eigen::Index k = 0; k < count; ++k) scratch[k] = distances[order_[begin + static_cast<std::size_t>(k)]];
  } else {
    for (const auto& values : features_) {
      const double reference = values[center];
      scratch.head(count) += (Eigen::Map<const Eigen::ArrayXd>(values.data() + begin, count) - reference).square();
    }
  }
  scratch = (scratch * -gamma_).exp();
  std::copy(scratch.data(), scratch.data() + count, out + begin);
}

// ---------------------------------------------------------------------------- cache

KernelCache::KernelCache(RbfKernel& kernel, double budget_mb)
    : kernel_(kernel), size_(kernel.size()), slot_of_(kernel.size(), -1), previous_(kernel.size() + 1),
      next_(kernel.size() + 1) {
  const double column_bytes = static_cast<double>(std::max<std::size_t>(size_, 1)) * sizeof(double);
  const double fitting = budget_mb * 1024.0 * 1024.0 / column_bytes;
  capacity_ = static_cast<std::size_t>(std::clamp(fitting, 2.0, static_cast<double>(std::max<std::size_t>(size_, 2))));
  const int sentinel = static_cast<int>(size_);
  previous_[size_] = sentinel;
  next_[size_] = sentinel;
}

void KernelCache::unlink(int sample) {
  next_[previous_[sample]] = next_[sample];
  previous_[next_[sample]] = previous_[sample];
}

void KernelCache::touch(int sample) {
  const int sentinel = static_cast<int>(size_);
  // most recently used sits just before the sentinel
  previous_[sample] = previous_[sentinel];
  next_[sample] = sentinel;
  next_[previous_[sentinel]] = sample;
  previous_[sentinel] = sample;
}

const double* KernelCache::column(int position, int length) {
  const int sample = kernel_.sample_at(static_cast<std::size_t>(position));
  int slot = slot_of_[sample];
  if (slot >= 0) {
    unlink(sample);
    touch(sample);
    if (length_of_slot_[slot] >= length) return slots_[slot].get();
  } else {
    if (slots_.size() < capacity_) {
      slot = static_cast<int>(slots_.size());
      slots_.push_back(std::make_unique<double[]>(size_));
      sample_of_slot_.push_back(-1);
      length_of_slot_.push_back(0);
    } else {
      const int evicted = next_[size_];  // least recently used
      slot = slot_of_[evicted];
      unlink(evicted);
      slot_of_[evicted] = -1;
    }
    slot_of_[sample] = slot;
    sample_of_slot_[slot] = sample;
    length_of_slot_[slot] = 0;
    touch(sample);
  }
  double* data = slots_[slot].get();
  kernel_.column(static_cast<std::size_t>(position), static_cast<std::size_t>(length_of_slot_[slot]),
                 static_cast<std::size_t>(length), data);
  length_of_slot_[slot] = length;
  ++columns_computed_;
  return data;
}

void KernelCache::swap(const std::vector<std::pair<int, int>>& position_pairs) {
  if (position_pairs.empty()) return;
  for (const auto& [a, b] : position_pairs) kernel_.swap(static_cast<std::size_t>(a), static_cast<std::size_t>(b));
  // Column by column, so that each column is walked once. Pairs are applied in order; an
  // entry that moves into a column's valid prefix from beyond it is computed afresh.
  for (std::size_t slot = 0; slot < slots_.size(); ++slot) {
    const int length = length_of_slot_[slot];
    if (length == 0) continue;
    double* data = slots_[slot].get();
    bool needs_fresh = false;
    for (const auto& [a, b] : position_pairs) {
      const int low = std::min(a, b), high = std::max(a, b);
      if (high < length) std::swap(data[low], data[high]);
      else if (low < length) needs_fresh = true;
    }
    if (needs_fresh) length_of_slot_[slot] = 0;  // rare: columns span the active set

  }
}

}  // namespace thermodrift::svr_detail
