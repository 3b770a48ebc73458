// An optional robust pre-filter for isolated outliers (single-sample spikes of a serial
// link or an ADC): a causal Hampel filter. Each sample is compared with the median of the
// `window` samples before it; further than `sigmas` robust standard deviations (1.4826 x
// their median absolute deviation) from it, it is replaced by that median. Causal, so the
// whole-file reader and the streaming compensate replace the same samples. Off unless
// asked for (`--despike`): a real step in the data is delayed, never removed, but a
// filter that changes data must be chosen (docs/data.md, "Spikes").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace thermodrift {

struct DespikeOptions {
  std::size_t window = 30;  // samples before the judged one (3 to 100000)
  double sigmas = 6;        // threshold in robust standard deviations (> 0)

  bool IsValid(std::string* why) const;
};

// One channel's filter.
class Despiker {
 public:
  explicit Despiker(const DespikeOptions& options);
  // The sample, or the median of the window before it when it is an outlier (*replaced
  // set). Until the window is full, samples pass unchanged. The window keeps the raw
  // samples, so a lasting step passes after about window / 2 samples.
  double push(double value, bool* replaced);
  void reset();  // forget the window (a new file)

 private:
  DespikeOptions options_;
  std::vector<double> history_;  // ring of the last `window` raw samples
  std::size_t next_ = 0;
  std::size_t count_ = 0;
  std::vector<double> scratch_;
};

}  // namespace thermodrift
