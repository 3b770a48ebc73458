// The Compensator's drift is the drift at the sample's own time, not the smoothed drift the
// model predicts, which lags it by half the smoothing window. Checked in closed form: a gyro
// whose drift is exactly c·(T - reference), a model c·dT on the 100 s trailing mean of T.
#include "thermodrift/compensate/compensator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace thermodrift {
namespace {

constexpr double kC = 0.5;           // °/h per °C
constexpr double kReference = 25.0;  // °C

DriftModel proportional_model(double smooth_seconds) {
  DriftModel model;
  AxisModel axis;
  axis.name = "gyro_x";
  axis.gyro_column = axis.temperature_column = "1";
  axis.pipeline.smooth_seconds = smooth_seconds;
  axis.pipeline.rate_span_seconds = 100;
  axis.pipeline.reference_temperature = kReference;
  axis.pipeline.terms = {FeatureTerm{FeatureTerm::Kind::delta_t}};
  axis.kind = ModelKind::linear;
  LinearModel linear;
  linear.regressors = linear_regressors(1);
  linear.coefficients = Eigen::VectorXd::Constant(1, kC);
  axis.model = linear;
  model.axes.push_back(axis);
  return model;
}

// A chamber programme: 20 °C soak, 1 °C/min up to 60 °C, soak, 1 °C/min down, soak.
double chamber(double t) {
  if (t < 1800) return 20;
  if (t < 4200) return 20 + (t - 1800) / 60;
  if (t < 6000) return 60;
  if (t < 8400) return 60 - (t - 6000) / 60;
  return 20;
}

struct Errors {
  double rms_instantaneous = 0;  // of the compensator's drift against the true drift
  double largest_on_ramps = 0;   // |drift - true| on the ramps, 300 s past their corners
};

Errors run(double smooth_seconds, double step_seconds) {
  Compensator compensator(proportional_model(smooth_seconds));
  Errors errors;
  double sum_instantaneous = 0;
  std::size_t count = 0;
  for (long i = 0; i * step_seconds <= 10000; ++i) {
    const double t = static_cast<double>(i) * step_seconds;  // steps exact in binary: no window that
                                                             // holds one sample more by rounding
    const std::vector<double> temperature{chamber(t)};
    const double drift = kC * (temperature[0] - kReference);
    const std::vector<double> gyro{10.0 + drift};
    const auto& out = compensator.push(t, gyro, temperature);
    EXPECT_DOUBLE_EQ(out.compensated[0], gyro[0] - out.drift[0]);
    if (t < 300) continue;
    const double error = out.drift[0] - drift;
    sum_instantaneous += error * error;
    ++count;
    const bool on_ramp = (t > 2100 && t < 4200) || (t > 6300 && t < 8400);
    if (on_ramp) errors.largest_on_ramps = std::max(errors.largest_on_ramps, std::abs(error));
  }
  errors.rms_instantaneous = std::sqrt(sum_instantaneous / static_cast<double>(count));
  return errors;
}

TEST(DriftAtSampleTime, OnARampItIsTheDriftItself) {
  // At 1 Hz the 100 s trailing mean of a ramp is the ramp 49.5 s before; its 10 s lag's
  // slope is the ramp's once settled: the advanced prediction is exact.
  const Errors errors = run(100, 1.0);
  EXPECT_LT(errors.largest_on_ramps, 1e-9) << "1 °C/min would leave 0.41 °/h behind";
  // Over the whole programme, corners included, a fraction of the smoothed prediction's
  // lag (0.5 °/h per °C × 49.5 s at 1 °C/min = 0.41 °/h on the ramps).
  EXPECT_LT(errors.rms_instantaneous, 0.05) << errors.rms_instantaneous;
}

TEST(DriftAtSampleTime, HoldsAtOtherSampleRates) {
  EXPECT_LT(run(100, 0.125).largest_on_ramps, 1e-8);
  EXPECT_LT(run(100, 5.0).largest_on_ramps, 1e-9);
}

TEST(DriftAtSampleTime, WithoutSmoothingThePredictionIsTheDrift) {
  EXPECT_LT(run(0, 1.0).largest_on_ramps, 1e-12);
}

// What the lag costs without the advance: the same model's prediction is 49.5 s behind.
TEST(DriftAtSampleTime, TheSmoothedPredictionLagsByHalfTheWindow) {
  const DriftModel model = proportional_model(100);
  FeatureStream stream(model.axes[0].pipeline);
  for (double t = 0; t <= 3000; ++t) {
    const auto& sample = stream.push(t, 0.0, chamber(t));
    if (t == 3000) {
      EXPECT_DOUBLE_EQ(sample.window_lag, 49.5);
      EXPECT_NEAR(model.axes[0].predict(sample.features), kC * (chamber(t - 49.5) - kReference), 1e-9);
    }
  }
}

}  // namespace
}  // namespace thermodrift
