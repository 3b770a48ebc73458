#include "thermodrift/compensate/readiness.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace thermodrift {

namespace {
// A unit one step too coarse or too fine (s for ms, ms for us, ...) is off by this.
constexpr double kUnitStep = 1000;
}  // namespace

ReadinessTally::ReadinessTally(const Pipeline& pipeline)
    : warm_up_seconds_(pipeline.warm_up_seconds()), gap_seconds_(pipeline.effective_gap_seconds()) {}

void ReadinessTally::add(double time, double since_start, bool ready) {
  if (samples_ > 0) {
    const double step = time - last_time_;
    shortest_step_ = std::min(shortest_step_, step);
    if (step > gap_seconds_) ++gaps_;
  }
  last_time_ = time;
  ++samples_;
  if (ready) ++ready_;
  longest_stretch_ = std::max(longest_stretch_, since_start);
}

std::string ReadinessTally::never_ready_reason() const {
  if (ready_ > 0) return {};
  if (samples_ == 0) return "no rows";
  if (samples_ > 1 && gaps_ == samples_ - 1) {
    return fmt::format("every time step was a gap (the shortest, {:g} s, is longer than the {:g} s gap threshold): "
                       "check --time-unit (a log in ms read as s has steps 1000 times too long)",
                       shortest_step_, gap_seconds_);
  }
  std::string reason = fmt::format("the longest stretch without a gap is {:g} s, shorter than the {:g} s warm-up "
                                   "(smoothing window + rate span)",
                                   longest_stretch_, warm_up_seconds_);
  if (gaps_ > 0) reason += fmt::format(", with {} steps longer than the {:g} s gap threshold", gaps_, gap_seconds_);
  if (longest_stretch_ * kUnitStep >= warm_up_seconds_) {
    reason += ": a log too short, or check --time-unit (a log in s read as ms is 1000 times too short)";
  }
  return reason;
}

}  // namespace thermodrift
