#include "thermodrift/sim/chamber_profile.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "thermodrift/error.hpp"

namespace thermodrift::sim {

ChamberProfile::ChamberProfile(const SimulatorOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw UsageError("simulator: " + error);

  double now_s = 0.0;
  double now_c = options.start_temperature_c;
  // Appends a ramp to `target_c` at the chamber rate, or a soak of `soak_min`.
  auto ramp_to = [&](double target_c) {
    const double duration_s = std::abs(target_c - now_c) / options.ramp_rate_c_per_min * 60.0;
    if (duration_s <= 0.0) return;
    segments_.push_back({now_s, now_s + duration_s, now_c, target_c});
    now_s += duration_s;
    now_c = target_c;
  };
  auto soak = [&](double soak_min) {
    if (soak_min <= 0.0) return;
    segments_.push_back({now_s, now_s + soak_min * 60.0, now_c, now_c});
    now_s += soak_min * 60.0;
  };

  const double first_extreme_c = options.heat_first ? options.chamber_max_c : options.chamber_min_c;
  const double second_extreme_c = options.heat_first ? options.chamber_min_c : options.chamber_max_c;
  for (int cycle = 0; cycle < options.cycles; ++cycle) {
    cycle_starts_s_.push_back(now_s);
    soak(options.start_soak_min);
    ramp_to(first_extreme_c);
    soak(options.extreme_soak_min);
    ramp_to(second_extreme_c);
    soak(options.extreme_soak_min);
    ramp_to(options.start_temperature_c);
  }
}

double ChamberProfile::temperature_c(double time_s) const {
  if (segments_.empty()) return 0.0;
  if (time_s <= segments_.front().start_s) return segments_.front().start_c;
  if (time_s >= segments_.back().end_s) return segments_.back().end_c;
  const auto segment = std::lower_bound(segments_.begin(), segments_.end(), time_s,
                                        [](const Segment& s, double t) { return s.end_s < t; });
  const double fraction = (time_s - segment->start_s) / (segment->end_s - segment->start_s);
  return segment->start_c + fraction * (segment->end_c - segment->start_c);
}

}  // namespace thermodrift::sim
