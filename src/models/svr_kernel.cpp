#include "svr_kernel.hpp"

#include "svr_simd.hpp"

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
// more than it saves. With the vectorised exp a 20,000-entry column takes ~20 µs, and at
// n = 20,000 two threads were no faster than one (docs/svr.md), so the split starts above.
constexpr std::size_t kParallelColumnLength = 32768;
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

namespace {

using simd::Lanes;
using simd::LaneMask;
using simd::broadcast;
using simd::negative_exp_lanes;

// Σ_f (columns[f][k + i] - center[f])² in lane i; only lanes i < rest (≤ 4) are read, the
// others are padded with the centre (distance 0).
__attribute__((always_inline)) inline Lanes squared_distance_lanes(const double* const* columns,
                                                                   std::size_t feature_count, const double* center,
                                                                   std::size_t k, std::size_t rest = simd::kLanes) {
  Lanes sum = broadcast(0.0);
  for (std::size_t f = 0; f < feature_count; ++f) {
    Lanes values;
    if (rest == simd::kLanes) {
      values = simd::load(columns[f] + k);
    } else {
      double padded[simd::kLanes] = {center[f], center[f], center[f], center[f]};
      std::memcpy(padded, columns[f] + k, rest * sizeof(double));
      values = simd::load(padded);
    }
    const Lanes difference = values - center[f];
    sum += difference * difference;
  }
  return sum;
}

// out[p] = exp(-gamma Σ_f (features[f][p] - center[f])²), p in [0, count). Lane-wise, so
// an entry's value does not depend on where in a range it sits (a column may be
// computed in pieces): the tail is padded to a whole vector.
THERMODRIFT_SIMD_CLONES
void rbf_entries(const double* const* features, std::size_t feature_count, const double* center, double gamma,
                 std::size_t count, double* out) {
  const Lanes factor = broadcast(-gamma);
  std::size_t p = 0;
  for (; p + simd::kLanes <= count; p += simd::kLanes)
    simd::store(out + p, negative_exp_lanes(squared_distance_lanes(features, feature_count, center, p), factor));
  if (p < count) {
    const std::size_t rest = count - p;
    double tail[simd::kLanes];
    simd::store(tail, negative_exp_lanes(squared_distance_lanes(features, feature_count, center, p, rest), factor));
    std::memcpy(out + p, tail, rest * sizeof(double));
  }
}

// values[p] = exp(-gamma values[p]) in place, p in [0, count).
THERMODRIFT_SIMD_CLONES
void negative_exp(double* values, std::size_t count, double gamma) {
  const Lanes factor = broadcast(-gamma);
  std::size_t p = 0;
  for (; p + simd::kLanes <= count; p += simd::kLanes)
    simd::store(values + p, negative_exp_lanes(simd::load(values + p), factor));
  if (p < count) {
    double tail[simd::kLanes] = {0, 0, 0, 0};
    std::memcpy(tail, values + p, (count - p) * sizeof(double));
    simd::store(tail, negative_exp_lanes(simd::load(tail), factor));
    std::memcpy(values + p, tail, (count - p) * sizeof(double));
  }
}

}  // namespace

THERMODRIFT_SIMD_CLONES
double rbf_sum(const double* const* columns, std::size_t feature_count, const double* x, double gamma,
               const double* coefficients, std::size_t count) {
  const Lanes factor = broadcast(-gamma);
  Lanes sum = broadcast(0.0);
  std::size_t k = 0;
  // Two vectors of lanes per step: their exp polynomials are independent chains.
  Lanes other_sum = broadcast(0.0);
  for (; k + 2 * simd::kLanes <= count; k += 2 * simd::kLanes) {
    Lanes squared = broadcast(0.0), other_squared = broadcast(0.0);
    for (std::size_t f = 0; f < feature_count; ++f) {
      const Lanes difference = simd::load(columns[f] + k) - x[f];
      const Lanes other_difference = simd::load(columns[f] + k + simd::kLanes) - x[f];
      squared += difference * difference;
      other_squared += other_difference * other_difference;
    }
    sum += simd::load(coefficients + k) * negative_exp_lanes(squared, factor);
    other_sum += simd::load(coefficients + k + simd::kLanes) * negative_exp_lanes(other_squared, factor);
  }
  sum += other_sum;
  for (; k + simd::kLanes <= count; k += simd::kLanes) {
    sum += simd::load(coefficients + k) * negative_exp_lanes(squared_distance_lanes(columns, feature_count, x, k), factor);
  }
  if (k < count) {  // the last vectors padded with zero coefficients
    const std::size_t rest = count - k;
    double weights[simd::kLanes] = {0, 0, 0, 0};
    std::memcpy(weights, coefficients + k, rest * sizeof(double));
    sum += simd::load(weights) * negative_exp_lanes(squared_distance_lanes(columns, feature_count, x, k, rest), factor);
  }
  double lanes[simd::kLanes];
  simd::store(lanes, sum);
  return (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
}

// Positions [begin, end) of one column, from the samples (feature-major, position
// order) or from the stored squared distances.
void RbfKernel::column_serial(std::size_t center, std::size_t begin, std::size_t end, double* out) const {
  if (end <= begin) return;
  if (data_.has_distances()) {
    const double* distances = data_.squared_distances().col(order_[center]).data();
    for (std::size_t position = begin; position < end; ++position) out[position] = distances[order_[position]];
    negative_exp(out + begin, end - begin, gamma_);
    return;
  }
  constexpr std::size_t kFewFeatures = 16;  // this tool uses 2-10; more take two passes
  const double* feature_ranges[kFewFeatures];
  double reference[kFewFeatures];
  if (features_.size() > kFewFeatures) {
    std::fill(out + begin, out + end, 0.0);
    for (const auto& values : features_) {
      const double at_center = values[center];
      for (std::size_t position = begin; position < end; ++position) {
        const double difference = values[position] - at_center;
        out[position] += difference * difference;
      }
    }
    negative_exp(out + begin, end - begin, gamma_);
    return;
  }
  for (std::size_t f = 0; f < features_.size(); ++f) {
    feature_ranges[f] = features_[f].data() + begin;
    reference[f] = features_[f][center];
  }
  rbf_entries(feature_ranges, features_.size(), reference, gamma_, end - begin, out + begin);
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
    catch_up(slot);
    if (length_of_slot_[slot] >= length) return slots_[slot].get();
  } else {
    if (slots_.size() < capacity_) {
      slot = static_cast<int>(slots_.size());
      slots_.push_back(std::make_unique_for_overwrite<double[]>(size_));  // no zero fill: written before read
      length_of_slot_.push_back(0);
      log_position_of_slot_.push_back(0);
    } else {
      const int evicted = next_[size_];  // least recently used
      slot = slot_of_[evicted];
      unlink(evicted);
      slot_of_[evicted] = -1;
    }
    slot_of_[sample] = slot;
    length_of_slot_[slot] = 0;
    log_position_of_slot_[slot] = swap_log_.size();
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
  for (const auto& [a, b] : position_pairs) {
    kernel_.swap(static_cast<std::size_t>(a), static_cast<std::size_t>(b));
    swap_log_.emplace_back(std::min(a, b), std::max(a, b));
  }
}

// Replays the exchanges made since the column was last used. Most cached columns are
// evicted before they are used again, so they never pay for the exchanges. An entry
// that moves into the valid prefix from beyond it cannot be swapped in: the column is
// then recomputed (rare: columns span the active set).
void KernelCache::catch_up(int slot) {
  const std::size_t from = log_position_of_slot_[slot];
  log_position_of_slot_[slot] = swap_log_.size();
  const int length = length_of_slot_[slot];
  double* data = slots_[slot].get();
  for (std::size_t k = from; k < swap_log_.size(); ++k) {
    const auto [low, high] = swap_log_[k];
    if (high < length) {
      std::swap(data[low], data[high]);
    } else if (low < length) {
      length_of_slot_[slot] = 0;
      return;
    }
  }
}

}  // namespace thermodrift::svr_detail
