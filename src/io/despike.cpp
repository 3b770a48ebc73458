#include "thermodrift/io/despike.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace thermodrift {

namespace {

double median_of(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  if (values.size() % 2 == 1) return *middle;
  return 0.5 * (*middle + *std::max_element(values.begin(), middle));
}

}  // namespace

bool DespikeOptions::IsValid(std::string* why) const {
  if (window < 3 || window > 100000) {
    if (why) *why = fmt::format("despike window must be 3 to 100000 samples (got {})", window);
    return false;
  }
  if (!(sigmas > 0 && std::isfinite(sigmas))) {
    if (why) *why = fmt::format("despike threshold must be a positive number of sigmas (got {:g})", sigmas);
    return false;
  }
  return true;
}

Despiker::Despiker(const DespikeOptions& options) : options_(options), history_(options.window) {}

void Despiker::reset() {
  next_ = 0;
  count_ = 0;
}

double Despiker::push(double value, bool* replaced) {
  *replaced = false;
  double out = value;
  if (count_ == history_.size()) {
    scratch_.assign(history_.begin(), history_.end());
    const double median = median_of(scratch_);
    double step = 0;  // the smallest nonzero deviation: a quantized signal's step
    for (double& x : scratch_) {
      x = std::abs(x - median);
      if (x > 0 && (step == 0 || x < step)) step = x;
    }
    // A quantized signal can have no spread (most samples on one level): a value one step
    // off is then no outlier. A window all on one level gives no scale at all; a jump of
    // `sigmas` % of the level (of at least 1 unit) is judged an outlier there.
    const double scale = step > 0 ? std::max(1.4826 * median_of(scratch_), step)
                                  : 0.01 * std::max(std::abs(median), 1.0);
    if (std::abs(value - median) > options_.sigmas * scale) {
      out = median;
      *replaced = true;
    }
  }
  history_[next_] = value;
  next_ = (next_ + 1) % history_.size();
  count_ = std::min(count_ + 1, history_.size());
  return out;
}

}  // namespace thermodrift
