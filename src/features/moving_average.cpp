#include "thermodrift/features/moving_average.hpp"

#include <cmath>

namespace thermodrift {

TrailingMean::TrailingMean(double window_seconds) : window_(window_seconds), ring_(16) {}

void TrailingMean::reset() {
  head_ = 0;
  count_ = 0;
  sum_ = 0;
  pushes_since_resum_ = 0;
}

void TrailingMean::grow() {
  std::vector<Sample> larger(ring_.size() * 2);
  for (std::size_t i = 0; i < count_; ++i) larger[i] = ring_[(head_ + i) % ring_.size()];
  ring_ = std::move(larger);
  head_ = 0;
}

double TrailingMean::push(double time, double value) {
  if (count_ == 0) first_time_ = time;
  newest_time_ = time;
  bool jump = false;
  while (count_ > 0 && ring_[head_].time <= time - window_) {
    const double leaving = ring_[head_].value;
    sum_ -= leaving;
    head_ = (head_ + 1) % ring_.size();
    --count_;
    // A value far larger than what stays took the others' digits with it when it was
    // added (1e300 + 20 is 1e300): the sum left is noise until re-added.
    jump = jump || std::abs(leaving) > kResumJump * (std::abs(sum_) + static_cast<double>(count_));
  }
  if (count_ == ring_.size()) grow();
  ring_[(head_ + count_) % ring_.size()] = {time, value};
  ++count_;
  sum_ += value;
  // A running sum drifts by rounding over millions of samples; re-adding the window
  // once per window length keeps it exact at O(1) amortised cost.
  if (++pushes_since_resum_ >= ring_.size() || jump) {
    sum_ = 0;
    for (std::size_t i = 0; i < count_; ++i) sum_ += ring_[(head_ + i) % ring_.size()].value;
    pushes_since_resum_ = 0;
  }
  return sum_ / static_cast<double>(count_);
}

}  // namespace thermodrift
