#include "thermodrift/optim/batch_evaluator.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

#include "thermodrift/error.hpp"

namespace thermodrift::optim {

namespace {

std::vector<double> Key(const Eigen::VectorXd& point) {
  return std::vector<double>(point.data(), point.data() + point.size());
}

double Sanitize(double value) { return std::isnan(value) ? BatchEvaluator::kNotEvaluated : value; }

}  // namespace

BatchEvaluator::BatchEvaluator(const Objective& objective, const Box& box, const RunControl& control)
    : objective_(objective), box_(box), control_(control), start_(std::chrono::steady_clock::now()) {
  box_.validate();
  std::string why;
  if (!control_.IsValid(&why)) throw UsageError(why);
  if (!objective_) throw UsageError("optim: the objective is empty");
}

long BatchEvaluator::remaining_evaluations() const {
  if (control_.max_evaluations <= 0) return std::numeric_limits<long>::max();
  return std::max(0L, control_.max_evaluations - evaluations_);
}

void BatchEvaluator::set_iteration(long iteration, double fraction_done) {
  iteration_ = iteration;
  fraction_done_ = fraction_done;
}

void BatchEvaluator::Report(double best, long evaluations) {
  if (!control_.callback || stopped_by_callback_) return;
  Progress progress;
  progress.iteration = iteration_;
  progress.evaluations = evaluations;
  progress.cache_hits = cache_hits_;
  progress.best_value = best;
  progress.elapsed_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  double fraction = fraction_done_;
  if (control_.max_evaluations > 0)
    fraction = std::max(fraction, static_cast<double>(evaluations) /
                                      static_cast<double>(control_.max_evaluations));
  progress.fraction_done = std::clamp(fraction, 0.0, 1.0);
  if (!control_.callback(progress)) stopped_by_callback_ = true;
}

double BatchEvaluator::evaluate(const Eigen::VectorXd& unit_point) {
  return evaluate(std::vector<Eigen::VectorXd>{unit_point}).front();
}

std::vector<double> BatchEvaluator::evaluate(const std::vector<Eigen::VectorXd>& unit_points) {
  const std::size_t count = unit_points.size();
  std::vector<double> values(count, kNotEvaluated);
  if (count == 0 || should_stop()) return values;

  // Which points need the objective: `pending` holds each distinct new point once, in
  // order of first appearance.
  std::vector<Eigen::VectorXd> user_points(count);
  std::vector<Eigen::VectorXd> pending;
  std::vector<std::size_t> pending_of_point(count, count);  // index into pending, or count
  std::vector<bool> from_cache(count, false);
  std::vector<bool> repeat_in_batch(count, false);  // same point earlier in this batch
  std::map<std::vector<double>, std::size_t> pending_index;
  for (std::size_t i = 0; i < count; ++i) {
    user_points[i] = box_.FromUnit(unit_points[i]);
    if (control_.cache) {
      auto key = Key(user_points[i]);
      if (auto hit = cache_.find(key); hit != cache_.end()) {
        values[i] = hit->second;
        from_cache[i] = true;
        continue;
      }
      if (auto same = pending_index.find(key); same != pending_index.end()) {
        pending_of_point[i] = same->second;
        repeat_in_batch[i] = true;
        continue;
      }
      pending_index.emplace(std::move(key), pending.size());
    }
    pending_of_point[i] = pending.size();
    pending.push_back(user_points[i]);
  }
  // The budget cuts the batch at its end, the same way for any thread count.
  pending.resize(static_cast<std::size_t>(
      std::min<long>(static_cast<long>(pending.size()), remaining_evaluations())));

  std::vector<double> pending_values(pending.size(), kNotEvaluated);
  std::vector<char> done(pending.size(), 0);
  const int workers = static_cast<int>(
      std::min<std::size_t>(static_cast<std::size_t>(std::max(1, control_.threads)), pending.size()));

  if (workers <= 1) {
    double provisional_best = best_value_;
    for (std::size_t k = 0; k < pending.size() && !stopped_by_callback_; ++k) {
      pending_values[k] = Sanitize(objective_(pending[k]));
      done[k] = 1;
      provisional_best = std::min(provisional_best, pending_values[k]);
      Report(provisional_best, evaluations_ + static_cast<long>(k) + 1);
    }
  } else {
    // Workers take the next pending point until none is left or a stop is asked; this
    // thread waits and reports each finished evaluation to the callback.
    std::mutex mutex;
    std::condition_variable finished_one;
    std::condition_variable acknowledged_one;
    std::size_t acknowledged = 0;
    std::atomic<std::size_t> next{0};
    std::atomic<bool> stop{false};
    std::size_t finished = 0;
    int running = workers;
    std::exception_ptr error;
    auto work = [&] {
      while (!stop.load()) {
        const std::size_t k = next.fetch_add(1);
        if (k >= pending.size()) break;
        double value = kNotEvaluated;
        std::exception_ptr thrown;
        try {
          value = Sanitize(objective_(pending[k]));
        } catch (...) {
          thrown = std::current_exception();
          stop.store(true);
        }
        std::unique_lock lock(mutex);
        if (thrown) {
          if (!error) error = thrown;
        } else {
          pending_values[k] = value;
          done[k] = 1;
          ++finished;
        }
        finished_one.notify_one();
        // Take no new point before the callback has heard of this one, so that a stop
        // lets at most the evaluations already running finish (one per other worker).
        const std::size_t mine = finished;
        acknowledged_one.wait(lock, [&] { return acknowledged >= mine || stop.load() || thrown; });
      }
      std::lock_guard lock(mutex);
      --running;
      finished_one.notify_one();
    };
    std::vector<std::thread> threads;
    threads.reserve(static_cast<std::size_t>(workers));
    for (int w = 0; w < workers; ++w) threads.emplace_back(work);

    std::size_t reported = 0;
    double provisional_best = best_value_;
    std::unique_lock lock(mutex);
    while (true) {
      finished_one.wait(lock, [&] { return finished > reported || running == 0; });
      if (finished == reported && running == 0) break;
      for (std::size_t k = 0; k < pending.size(); ++k)
        if (done[k]) provisional_best = std::min(provisional_best, pending_values[k]);
      reported = finished;
      lock.unlock();  // the callback may be slow (drawing a progress bar)
      Report(provisional_best, evaluations_ + static_cast<long>(reported));
      if (stopped_by_callback_) stop.store(true);
      lock.lock();
      acknowledged = reported;
      acknowledged_one.notify_all();
    }
    lock.unlock();
    for (auto& thread : threads) thread.join();
    if (error) std::rethrow_exception(error);
  }

  // Feed back in batch order: this is what makes the run independent of the threads.
  long evaluated = 0;
  for (std::size_t k = 0; k < pending.size(); ++k) {
    if (!done[k]) continue;
    ++evaluated;
    if (control_.cache) cache_.emplace(Key(pending[k]), pending_values[k]);
  }
  evaluations_ += evaluated;
  for (std::size_t i = 0; i < count; ++i) {
    if (from_cache[i]) {
      ++cache_hits_;
    } else {
      const std::size_t k = pending_of_point[i];
      if (k >= pending.size() || !done[k]) continue;  // cut by the budget or a stop
      values[i] = pending_values[k];
      if (repeat_in_batch[i]) ++cache_hits_;
    }
    if (values[i] < best_value_) {
      best_value_ = values[i];
      best_point_ = user_points[i];
      best_unit_point_ = unit_points[i].cwiseMax(0.0).cwiseMin(1.0);
    }
  }
  if (evaluated > 0) history_.push_back({evaluations_, best_value_});
  Report(best_value_, evaluations_);
  return values;
}

OptimizationResult BatchEvaluator::Result(Termination otherwise, long iterations) const {
  OptimizationResult result;
  result.best_point = best_point_;
  result.best_value = best_value_;
  result.evaluations = evaluations_;
  result.cache_hits = cache_hits_;
  result.iterations = iterations;
  result.history = history_;
  if (stopped_by_callback_)
    result.termination = Termination::stopped_by_callback;
  else if (budget_exhausted())
    result.termination = Termination::budget_exhausted;
  else
    result.termination = otherwise;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return result;
}

}  // namespace thermodrift::optim
