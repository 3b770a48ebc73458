// The training envelope: the range of conditions a drift model was fitted on, stored per
// axis in the model file, so that evaluation and compensation can say when the model is
// asked to extrapolate. One test (TrainingEnvelope::check) serves every command.
//
// A ready sample is outside the envelope when
//   - its smoothed temperature is outside [min - m, max + m], m = max(2 % of the
//     training range, 1 °C);
//   - its smoothed rate dT/dt is outside [min - m, max + m], m = max(10 % of the training
//     rate range, 0.05 °C/min);
//   - it is heating (rate > +0.2 °C/min, kDirectionRateScale) and the training log never
//     was, or cooling (rate < -0.2 °C/min) and the training log never was.
// The margins keep the smoothing noise of a log like the training one from flagging its
// own extremes. Term ranges are recorded for the reader (and a deployed check on the
// raw model inputs); they take no part in the test.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "thermodrift/features/pipeline.hpp"

namespace thermodrift {

struct Range {
  double min = 0;
  double max = 0;
  bool operator==(const Range&) const = default;
};

// Which limits one sample crosses; all false: inside.
struct Excursion {
  bool temperature_low = false;
  bool temperature_high = false;
  bool rate_low = false;
  bool rate_high = false;
  bool heating_unseen = false;  // heating beyond +0.2 °C/min, never seen in training
  bool cooling_unseen = false;  // cooling beyond -0.2 °C/min, never seen in training
  bool temperature() const { return temperature_low || temperature_high; }
  bool rate() const { return rate_low || rate_high; }
  bool direction() const { return heating_unseen || cooling_unseen; }
  bool any() const { return temperature() || rate() || direction(); }
};

struct TrainingEnvelope {
  static constexpr double kTemperatureMarginFraction = 0.02;
  static constexpr double kTemperatureMarginMinimum = 1.0;  // °C
  static constexpr double kRateMarginFraction = 0.10;
  static constexpr double kRateMarginMinimum = 0.05;        // °C/min

  Range temperature;          // smoothed, °C
  Range rate;                 // smoothed dT/dt, °C/min
  bool heating_seen = false;  // some rate > +kDirectionRateScale
  bool cooling_seen = false;  // some rate < -kDirectionRateScale
  std::vector<Range> terms;   // one per pipeline term, in its order

  // The envelope of the ready samples of `table` (at least one row; UsageError otherwise).
  static TrainingEnvelope of(const FeatureTable& table);

  // The limits with their margins.
  Range temperature_limits() const;
  Range rate_limits() const;
  // The one test every command uses.
  Excursion check(double smoothed_temperature, double smoothed_rate) const;

  // What the training log did not cover that a model is usually asked: one sentence each.
  std::vector<std::string> coverage_warnings() const;
  // One line: "T -40.1..59.8 °C, dT/dt -1.00..1.00 °C/min, heating and cooling seen".
  std::string brief() const;

  nlohmann::json to_json() const;
  // Throws Error when a value is not finite, a min exceeds its max or the term ranges
  // are not one per term (`terms`).
  static TrainingEnvelope from_json(const nlohmann::json& json, std::size_t terms);
};

// Counts of the samples outside an envelope, by limit.
struct EnvelopeTally {
  std::size_t samples = 0;  // checked (ready) samples
  std::size_t outside = 0;
  std::size_t temperature_low = 0, temperature_high = 0, rate_low = 0, rate_high = 0;
  std::size_t heating_unseen = 0, cooling_unseen = 0;

  void add(const Excursion& excursion);
  std::size_t temperature() const { return temperature_low + temperature_high; }
  std::size_t rate() const { return rate_low + rate_high; }
  std::size_t direction() const { return heating_unseen + cooling_unseen; }
  double outside_fraction() const { return samples ? static_cast<double>(outside) / static_cast<double>(samples) : 0.0; }
  // The limits crossed, with their values: "temperature above 60.3 °C, cooling never seen".
  std::string describe(const TrainingEnvelope& envelope) const;
};

// The tally of the rows of `table` against `envelope`.
EnvelopeTally tally_outside(const TrainingEnvelope& envelope, const FeatureTable& table);

}  // namespace thermodrift
