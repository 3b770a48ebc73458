// Why a compensated stream was not trusted: the compensator's warm-up and gap rules
// (features/pipeline.hpp) followed on the time stamps of one axis, so that `compensate`
// can say at the end of a file whether every step was a gap (a log in ms read as s, say)
// or the log was shorter than the warm-up (one in s read as ms).
#pragma once

#include <cstddef>
#include <limits>
#include <string>

#include "thermodrift/features/pipeline.hpp"

namespace thermodrift {

class ReadinessTally {
 public:
  explicit ReadinessTally(const Pipeline& pipeline);

  // One sample of the axis: its time (s), and what the compensator said of it.
  void add(double time, double since_start, bool ready);

  std::size_t samples() const { return samples_; }
  std::size_t ready() const { return ready_; }
  std::size_t not_ready() const { return samples_ - ready_; }
  std::size_t gaps() const { return gaps_; }                       // steps longer than the gap threshold
  double longest_stretch_seconds() const { return longest_stretch_; }  // without a gap

  // Why no sample was ready, as one clause ("every time step was a gap ..."); empty when
  // one was.
  std::string never_ready_reason() const;

 private:
  double warm_up_seconds_;
  double gap_seconds_;
  std::size_t samples_ = 0;
  std::size_t ready_ = 0;
  std::size_t gaps_ = 0;
  double last_time_ = 0;
  double shortest_step_ = std::numeric_limits<double>::infinity();
  double longest_stretch_ = 0;
};

}  // namespace thermodrift
