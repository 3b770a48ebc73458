// Trailing (causal) moving average over a window in seconds, O(1) per sample, for
// irregularly sampled series.
#pragma once

#include <cstddef>
#include <vector>

namespace thermodrift {

class TrailingMean {
 public:
  // A value leaving the window that is more than this many times |sum left| + count
  // (a floor of one unit per sample, so a mean near 0 is no trigger) re-sums the window
  // at once rather than at the next periodic re-sum. The exported C header does the same.
  static constexpr double kResumJump = 1048576.0;  // 2^20

  // Mean of the samples whose time lies in (t - window, t]. A window of 0 passes each
  // sample through.
  explicit TrailingMean(double window_seconds);

  // Adds a sample (time strictly after the previous one) and returns the current mean.
  double push(double time, double value);

  // True once the samples seen since the last reset span the whole window.
  bool full() const { return count_ > 0 && newest_time_ - first_time_ >= window_; }
  double mean() const { return count_ == 0 ? 0.0 : sum_ / static_cast<double>(count_); }
  // Time of the oldest sample in the window (the newest's when the window is empty of
  // others; 0 before the first push): (newest - oldest) / 2 is how far the mean of an
  // evenly sampled signal lags its newest sample.
  double oldest_time() const { return count_ == 0 ? 0.0 : ring_[head_].time; }
  void reset();

 private:
  struct Sample {
    double time;
    double value;
  };
  void grow();

  double window_;
  std::vector<Sample> ring_;  // capacity grows to the largest window population seen
  std::size_t head_ = 0;      // index of the oldest sample
  std::size_t count_ = 0;
  double sum_ = 0;
  std::size_t pushes_since_resum_ = 0;
  double first_time_ = 0;  // first sample since reset
  double newest_time_ = 0;
};

}  // namespace thermodrift
