#include "thermodrift/compensate/compensator.hpp"

#include <cmath>
#include <limits>

#include "thermodrift/error.hpp"
#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift {

Compensator::Compensator(DriftModel model)
    : model_(std::move(model)), drift_(model_.axes.size()), trend_(model_.axes.size()), previous_smoothed_(model_.axes.size()),
      compensated_(model_.axes.size()),
      status_(model_.axes.size()) {
  for (const auto& axis : model_.axes) {
    if (axis.pipeline.libsvm) {
      throw UsageError("a model fitted on libsvm-format data has no chamber-log pipeline to compensate with");
    }
  }
  streams_.reserve(model_.axes.size());
  for (const auto& axis : model_.axes) streams_.emplace_back(axis.pipeline);
  output_.drift = drift_;
  output_.compensated = compensated_;
  output_.axes = status_;
}

void Compensator::reset() {
  for (auto& stream : streams_) stream.reset();
}

const Compensator::Output& Compensator::push(double time, std::span<const double> gyro,
                                             std::span<const double> temperatures) {
  // A sample with a non-finite input, or one beyond the physical ranges a log is read with
  // (a failed sensor read, a corrupted word), is rejected whole: it would stay in the
  // running sums and lag states for good. The state is left as it was.
  bool plausible = std::isfinite(time);
  for (std::size_t a = 0; a < streams_.size(); ++a) plausible = plausible && plausible_rate(gyro[a]);
  for (std::size_t c = 0; c < model_.temperature_inputs(); ++c) {
    plausible = plausible && plausible_temperature(temperatures[c]);
  }
  if (!plausible) {
    ++rejected_;
    for (std::size_t a = 0; a < streams_.size(); ++a) {
      drift_[a] = compensated_[a] = std::numeric_limits<double>::quiet_NaN();
      status_[a].ready = false;
      status_[a].outside_envelope = Excursion{};
    }
    output_.ready = false;
    return output_;
  }
  bool ready = true;
  for (std::size_t a = 0; a < streams_.size(); ++a) {
    const auto& sample = streams_[a].push(time, gyro[a], temperatures[model_.axes[a].pipeline.temperature_input(a)], temperatures);
    const double smoothed = model_.axes[a].predict(sample.features);
    // Advanced by the window's lag along its slope (as the exported C header computes it,
    // operation for operation): the slope from a τ-lag q of the prediction, stepped
    // exactly for an input that moves in a straight line between samples, so that on a
    // ramp q is the prediction τ before, whatever the step.
    const double tau = kDriftSlopeFraction * model_.axes[a].pipeline.smooth_seconds;
    if (tau > 0) {
      const double step = sample.step_seconds;
      if (step > 0) {
        const double decay = std::exp(-step / tau);
        trend_[a] = decay * trend_[a] + (1.0 - decay) * smoothed +
                    (smoothed - previous_smoothed_[a]) * (decay - (1.0 - decay) * (tau / step));
      } else {
        trend_[a] = smoothed;
      }
      drift_[a] = smoothed + sample.window_lag / tau * (smoothed - trend_[a]);
    } else {
      drift_[a] = smoothed;
    }
    previous_smoothed_[a] = smoothed;
    compensated_[a] = gyro[a] - drift_[a];
    const auto& envelope = model_.axes[a].envelope;
    // Never a non-finite value flagged valid (absurd inputs can overflow the model).
    status_[a].ready = sample.ready && std::isfinite(compensated_[a]);
    status_[a].since_start = sample.since_start;
    status_[a].outside_envelope = sample.ready && envelope
                                      ? envelope->check(sample.smoothed_temperature, sample.smoothed_rate)
                                      : Excursion{};
    ready = ready && status_[a].ready;
  }
  output_.ready = ready;
  return output_;
}

}  // namespace thermodrift
