#include "thermodrift/features/envelope.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace {

Range widened(const Range& range, double fraction, double minimum) {
  const double margin = std::max(fraction * (range.max - range.min), minimum);
  return {range.min - margin, range.max + margin};
}

void include(Range& range, double value) {
  range.min = std::min(range.min, value);
  range.max = std::max(range.max, value);
}

nlohmann::json range_json(const Range& range) { return nlohmann::json::array({range.min, range.max}); }

Range range_from_json(const nlohmann::json& json, const std::string& what) {
  if (!json.is_array() || json.size() != 2) throw Error(fmt::format("training envelope: {} must be [min, max]", what));
  // JSON has no infinity: a non-finite value was written as null.
  if (!json[0].is_number() || !json[1].is_number() || !std::isfinite(json[0].get<double>()) ||
      !std::isfinite(json[1].get<double>())) {
    throw Error(fmt::format("training envelope: {} is not finite", what));
  }
  const Range range{json[0].get<double>(), json[1].get<double>()};
  if (range.min > range.max) throw Error(fmt::format("training envelope: {} has min > max", what));
  return range;
}

}  // namespace

TrainingEnvelope TrainingEnvelope::of(const FeatureTable& table) {
  if (table.rows() == 0) throw UsageError("a training envelope needs at least one ready sample");
  TrainingEnvelope envelope;
  envelope.temperature = {table.temperature.front(), table.temperature.front()};
  envelope.rate = {table.rate.front(), table.rate.front()};
  for (std::size_t i = 0; i < table.rows(); ++i) {
    include(envelope.temperature, table.temperature[i]);
    include(envelope.rate, table.rate[i]);
  }
  envelope.heating_seen = envelope.rate.max > kDirectionRateScale;
  envelope.cooling_seen = envelope.rate.min < -kDirectionRateScale;
  for (Eigen::Index j = 0; j < table.features.cols(); ++j) {
    envelope.terms.push_back({table.features.col(j).minCoeff(), table.features.col(j).maxCoeff()});
  }
  return envelope;
}

Range TrainingEnvelope::temperature_limits() const {
  return widened(temperature, kTemperatureMarginFraction, kTemperatureMarginMinimum);
}

Range TrainingEnvelope::rate_limits() const { return widened(rate, kRateMarginFraction, kRateMarginMinimum); }

Excursion TrainingEnvelope::check(double smoothed_temperature, double smoothed_rate) const {
  const Range t = temperature_limits();
  const Range r = rate_limits();
  Excursion excursion;
  excursion.temperature_low = smoothed_temperature < t.min;
  excursion.temperature_high = smoothed_temperature > t.max;
  excursion.rate_low = smoothed_rate < r.min;
  excursion.rate_high = smoothed_rate > r.max;
  excursion.heating_unseen = !heating_seen && smoothed_rate > kDirectionRateScale;
  excursion.cooling_unseen = !cooling_seen && smoothed_rate < -kDirectionRateScale;
  return excursion;
}

std::vector<std::string> TrainingEnvelope::coverage_warnings() const {
  std::vector<std::string> warnings;
  if (!heating_seen && !cooling_seen) {
    warnings.push_back(fmt::format("the training rate stays within ±{:g} °C/min (a soak-only log): the rate terms "
                                   "are unidentifiable and the output on any ramp is an extrapolation",
                                   kDirectionRateScale));
    return warnings;
  }
  if (!heating_seen) {
    warnings.push_back("the model has never seen heating: its output while heating is an extrapolation");
  }
  if (!cooling_seen) {
    warnings.push_back("the model has never seen cooling: its output while cooling is an extrapolation");
  }
  return warnings;
}

std::string TrainingEnvelope::brief() const {
  const char* directions = heating_seen && cooling_seen ? "heating and cooling seen"
                           : heating_seen               ? "heating seen, cooling never"
                           : cooling_seen               ? "cooling seen, heating never"
                                                        : "neither heating nor cooling seen";
  return fmt::format("T {:.1f}..{:.1f} °C, dT/dt {:.2f}..{:.2f} °C/min, {}", temperature.min, temperature.max,
                     rate.min, rate.max, directions);
}

nlohmann::json TrainingEnvelope::to_json() const {
  nlohmann::json ranges = nlohmann::json::array();
  for (const auto& range : terms) ranges.push_back(range_json(range));
  return {{"temperature_c", range_json(temperature)},
          {"rate_c_per_min", range_json(rate)},
          {"heating_seen", heating_seen},
          {"cooling_seen", cooling_seen},
          {"terms", ranges}};
}

TrainingEnvelope TrainingEnvelope::from_json(const nlohmann::json& json, std::size_t terms) {
  if (!json.is_object()) throw Error("training envelope must be an object");
  TrainingEnvelope envelope;
  envelope.temperature = range_from_json(json.at("temperature_c"), "temperature_c");
  envelope.rate = range_from_json(json.at("rate_c_per_min"), "rate_c_per_min");
  envelope.heating_seen = json.at("heating_seen").get<bool>();
  envelope.cooling_seen = json.at("cooling_seen").get<bool>();
  const auto& ranges = json.at("terms");
  if (!ranges.is_array() || ranges.size() != terms) {
    throw Error(fmt::format("training envelope: {} term ranges for {} terms", ranges.is_array() ? ranges.size() : 0,
                            terms));
  }
  for (std::size_t j = 0; j < terms; ++j) envelope.terms.push_back(range_from_json(ranges[j], fmt::format("term {}", j + 1)));
  return envelope;
}

void EnvelopeTally::add(const Excursion& excursion) {
  ++samples;
  if (!excursion.any()) return;
  ++outside;
  temperature_low += excursion.temperature_low;
  temperature_high += excursion.temperature_high;
  rate_low += excursion.rate_low;
  rate_high += excursion.rate_high;
  heating_unseen += excursion.heating_unseen;
  cooling_unseen += excursion.cooling_unseen;
}

std::string EnvelopeTally::describe(const TrainingEnvelope& envelope) const {
  const Range t = envelope.temperature_limits();
  const Range r = envelope.rate_limits();
  std::vector<std::string> parts;
  if (temperature_low) parts.push_back(fmt::format("temperature below {:.1f} °C", t.min));
  if (temperature_high) parts.push_back(fmt::format("temperature above {:.1f} °C", t.max));
  if (rate_low) parts.push_back(fmt::format("rate below {:.2f} °C/min", r.min));
  if (rate_high) parts.push_back(fmt::format("rate above {:.2f} °C/min", r.max));
  if (heating_unseen) parts.push_back("heating never seen in training");
  if (cooling_unseen) parts.push_back("cooling never seen in training");
  return fmt::format("{}", fmt::join(parts, ", "));
}

EnvelopeTally tally_outside(const TrainingEnvelope& envelope, const FeatureTable& table) {
  EnvelopeTally tally;
  for (std::size_t i = 0; i < table.rows(); ++i) tally.add(envelope.check(table.temperature[i], table.rate[i]));
  return tally;
}

}  // namespace thermodrift
