// The chamber air temperature setpoint: piecewise-linear ramps and soaks, cycle after
// cycle. The chamber is assumed to follow its setpoint exactly; the lags are in the unit.
#pragma once

#include <vector>

#include "thermodrift/sim/options.hpp"

namespace thermodrift::sim {

class ChamberProfile {
 public:
  // One straight piece of the profile: a ramp, or a soak when the temperatures are equal.
  struct Segment {
    double start_s = 0.0;
    double end_s = 0.0;
    double start_c = 0.0;
    double end_c = 0.0;
  };

  // Throws UsageError when the options are not valid.
  explicit ChamberProfile(const SimulatorOptions& options);

  // Chamber temperature at time t (clamped to the ends of the profile).
  double temperature_c(double time_s) const;
  double duration_s() const { return segments_.empty() ? 0.0 : segments_.back().end_s; }
  // Time at which each cycle starts; cycle i runs from [i] to [i+1] (or the end).
  const std::vector<double>& cycle_starts_s() const { return cycle_starts_s_; }
  const std::vector<Segment>& segments() const { return segments_; }

 private:
  std::vector<Segment> segments_;
  std::vector<double> cycle_starts_s_;
};

}  // namespace thermodrift::sim
