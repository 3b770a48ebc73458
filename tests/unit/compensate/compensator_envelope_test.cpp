// The streaming Compensator says per sample and axis whether it is ready and whether the
// sample lies outside the model's training envelope: the check is the library's.
#include "thermodrift/compensate/compensator.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace thermodrift {
namespace {

DriftModel one_axis_model(std::optional<TrainingEnvelope> envelope) {
  DriftModel model;
  AxisModel axis;
  axis.name = "gyro_x";
  axis.gyro_column = axis.temperature_column = "1";
  axis.pipeline.smooth_seconds = 10;
  axis.pipeline.rate_span_seconds = 10;
  axis.pipeline.reference_temperature = 25;
  axis.kind = ModelKind::linear;
  LinearModel linear;
  linear.regressors = linear_regressors(2);
  linear.coefficients = Eigen::Vector2d(0.5, 0.25);
  axis.model = linear;
  axis.envelope = envelope;
  model.axes.push_back(axis);
  return model;
}

TrainingEnvelope soak_envelope() {  // 20..30 °C, soaks only
  TrainingEnvelope envelope;
  envelope.temperature = {20, 30};
  envelope.rate = {-0.1, 0.1};
  envelope.terms = {{-5, 5}, {-0.1, 0.1}};
  return envelope;
}

TEST(CompensatorEnvelope, ReadySamplesOutsideAreFlaggedWithTheirLimit) {
  Compensator compensator(one_axis_model(soak_envelope()));
  std::vector<double> gyro{1.0}, temperature{25.0};
  const auto& first = compensator.push(0, gyro, temperature);
  ASSERT_EQ(first.axes.size(), 1u);
  EXPECT_FALSE(first.axes[0].ready);
  EXPECT_FALSE(first.axes[0].outside_envelope.any());  // not checked in the warm-up
  double time = 1;
  for (; time <= 30; ++time) compensator.push(time, gyro, temperature);
  EXPECT_TRUE(compensator.push(time++, gyro, temperature).axes[0].ready);
  EXPECT_FALSE(compensator.push(time++, gyro, temperature).axes[0].outside_envelope.any());
  temperature[0] = 50;  // a jump: the smoothed temperature and its rate climb
  Excursion seen;
  for (int i = 0; i < 30; ++i) {
    const auto& status = compensator.push(time++, gyro, temperature).axes[0];
    seen.temperature_high |= status.outside_envelope.temperature_high;
    seen.heating_unseen |= status.outside_envelope.heating_unseen;
    seen.rate_high |= status.outside_envelope.rate_high;
  }
  EXPECT_TRUE(seen.temperature_high);
  EXPECT_TRUE(seen.heating_unseen);
  EXPECT_TRUE(seen.rate_high);
}

TEST(CompensatorEnvelope, AModelWithoutAnEnvelopeFlagsNothing) {
  Compensator compensator(one_axis_model(std::nullopt));
  std::vector<double> gyro{1.0}, temperature{80.0};
  for (double time = 0; time < 40; ++time) {
    EXPECT_FALSE(compensator.push(time, gyro, temperature).axes[0].outside_envelope.any());
  }
}

}  // namespace
}  // namespace thermodrift
