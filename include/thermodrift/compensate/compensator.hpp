// Real-time compensation: push one sample (time, gyro rates, temperatures), get the
// compensated rates. Only the past is used, through the same FeatureStream the model was
// fitted with; no allocation per sample once warmed up.
#pragma once

#include <span>
#include <vector>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/models/model_file.hpp"

namespace thermodrift {

class Compensator {
 public:
  explicit Compensator(DriftModel model);
  Compensator(const Compensator&) = delete;  // streams point into the model
  Compensator& operator=(const Compensator&) = delete;

  std::size_t axes() const { return model_.axes.size(); }
  const DriftModel& model() const { return model_; }

  // How far to trust one axis' output for this sample.
  struct AxisStatus {
    bool ready = false;          // false during this axis' warm-up (start or after a gap)
    double since_start = 0;      // s since this axis' pipeline (re)started
    // The ready sample against the model's training envelope (features/envelope.hpp);
    // all false while not ready or when the model file has no envelope.
    Excursion outside_envelope;
  };

  // The model predicts the drift of the smoothed output: the mean over the smoothing
  // window, which lags the drift at the newest sample by half the window (50 s for 100 s).
  // `drift` is the drift at the sample's own time: that prediction p advanced by the
  // window's lag L (FeatureStream::Sample::window_lag) along its slope, p + L · (p - q) / τ,
  // q a τ-lag of p stepped exactly for p moving in a straight line between samples (on a
  // ramp q is p τ before, so the slope is the ramp's; unlike a difference of two samples it
  // does not amplify a float header's rounding at a fast sample rate), τ =
  // kDriftSlopeFraction of the window; p itself at a (re)start. Subtracted from the raw
  // rate it leaves no lag on a ramp, and the compensated rate, smoothed as fit smoothed, is
  // what evaluate judges (docs/export.md, "The drift at the sample's time").
  static constexpr double kDriftSlopeFraction = 0.1;

  struct Output {
    std::span<const double> drift;        // drift per axis at this sample's time, °/h
    std::span<const double> compensated;  // gyro - drift per axis, °/h
    std::span<const AxisStatus> axes;     // per axis
    bool ready = false;                   // every axis ready
  };

  // `gyro` in °/h, one per axis; `temperatures`, one per axis then the model's extra
  // channels (model().temperature_inputs() in all). `time` must increase. A sample with
  // any non-finite input, a temperature beyond -273.15..1000 °C or a rate beyond
  // ±3.6e8 °/h (plausible_temperature, plausible_rate: the ranges a log is read with)
  // is rejected (counted in rejected()): not ready, drift and
  // compensated NaN, the state untouched; an axis whose output is not finite is not ready.
  // During warm-up the drift is predicted from the history there is (a partial window,
  // a shorter rate span): the best causal estimate, flagged by ready = false.
  const Output& push(double time, std::span<const double> gyro, std::span<const double> temperatures);
  void reset();
  std::size_t rejected() const { return rejected_; }  // samples with a non-finite or implausible input

 private:
  DriftModel model_;
  std::vector<FeatureStream> streams_;
  std::vector<double> drift_;
  std::vector<double> trend_;              // per axis, q: the τ-lag of the model's prediction
  std::vector<double> previous_smoothed_;  // per axis, the prediction at the previous sample
  std::vector<double> compensated_;
  std::vector<AxisStatus> status_;
  Output output_;
  std::size_t rejected_ = 0;
};

}  // namespace thermodrift
