// Issue 2's acceptance checks at library level: the in-sample residual of the linear
// model on simulated data equals a closed-form least-squares check, and a linear fit
// over both real BMI270 logs shows their bias-vs-temperature slope.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "../support/shared_data.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {
namespace {

// One simulated chamber cycle at 1 Hz as a 3-axis log, each axis with its own temperature.
ChamberLog simulated_cycle() {
  sim::SimulatorOptions options;
  options.cycles = 1;
  options.seed = 3;
  return sim::to_chamber_log(sim::simulate(options));
}

LogSpec simulated_spec() {
  LogSpec spec;
  spec.time_column = "time_s";
  spec.gyro_columns = {"gyro_x", "gyro_y", "gyro_z"};
  spec.temperature_columns = {"temp_x", "temp_y", "temp_z"};
  return spec;
}

// Mean squared residual of the ordinary least-squares fit of `target` on [1, features],
// from the normal equations (an independent closed form, not the library's QR).
double closed_form_mse(const Eigen::MatrixXd& features, const Eigen::VectorXd& target) {
  Eigen::MatrixXd design(features.rows(), features.cols() + 1);
  design.col(0).setOnes();
  design.rightCols(features.cols()) = features;
  const Eigen::VectorXd beta = (design.transpose() * design).ldlt().solve(design.transpose() * target);
  return (target - design * beta).squaredNorm() / static_cast<double>(target.size());
}

TEST(LinearAcceptance, InSampleResidualOnSimulatedDataMatchesClosedForm) {
  const std::vector<ChamberLog> logs = {simulated_cycle()};
  CalibrationOptions options;
  options.model = ModelKind::linear;
  options.decimation = 1;  // fit on every ready sample, so in-sample = the least-squares residual
  const Calibration calibration = calibrate(logs, simulated_spec(), options);
  ASSERT_EQ(calibration.axes.size(), 3u);
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const Pipeline& pipeline = calibration.model.axes[axis].pipeline;
    EXPECT_EQ(pipeline.term_names(), (std::vector<std::string>{"dT", "rate"}));
    const FeatureTable table = feature_table(logs, pipeline, axis, false);
    ASSERT_GT(table.rows(), 20000u);
    const double want = closed_form_mse(table.features, table.target);
    const double got = calibration.axes[axis].in_sample.mse_after;
    EXPECT_EQ(calibration.axes[axis].in_sample.samples, table.rows());
    EXPECT_LT(std::abs(got - want) / want, 1e-9) << "axis " << axis << ": " << got << " vs " << want;
    // And the model explains most of the drift.
    EXPECT_LT(got, 0.5 * calibration.axes[axis].in_sample.mse_before) << "axis " << axis;
  }
}

TEST(LinearAcceptance, DecimatedFitIsTheClosedFormOnTheKeptSamples) {
  const std::vector<ChamberLog> logs = {simulated_cycle()};
  CalibrationOptions options;
  options.model = ModelKind::linear;  // default decimation: every 10th ready sample
  const Calibration calibration = calibrate(logs, simulated_spec(), options);
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto& model = calibration.model.axes[axis];
    EXPECT_EQ(model.pipeline.decimation, 10u);
    const FeatureTable kept = feature_table(logs, model.pipeline, axis, true);
    EXPECT_EQ(calibration.axes[axis].training_samples, kept.rows());
    Eigen::MatrixXd design(kept.features.rows(), 3);
    design.col(0).setOnes();
    design.rightCols(2) = kept.features;
    const Eigen::VectorXd beta = (design.transpose() * design).ldlt().solve(design.transpose() * kept.target);
    // In-sample metrics are over every ready sample, with the model fitted on the kept ones.
    const FeatureTable every = feature_table(logs, model.pipeline, axis, false);
    Eigen::MatrixXd all(every.features.rows(), 3);
    all.col(0).setOnes();
    all.rightCols(2) = every.features;
    const double want = (every.target - all * beta).squaredNorm() / static_cast<double>(every.rows());
    const double got = calibration.axes[axis].in_sample.mse_after;
    EXPECT_LT(std::abs(got - want) / want, 1e-9) << "axis " << axis;
  }
}

TEST(Bmi270Acceptance, LinearFitOverBothLogsShowsTheBiasSlope) {
  THERMODRIFT_SKIP_WITHOUT_SHARED_DATA("real/bmi270");
  LogSpec spec;
  spec.rate_hz = 50;
  spec.temperature_columns = {"1"};
  spec.gyro_columns = {"5", "6", "7"};
  spec.gyro_unit = GyroUnit::dps;
  const std::string folder = testing::shared_data("real/bmi270/");
  const std::vector<ChamberLog> logs = {read_chamber_log(folder + "cold.csv", spec),
                                        read_chamber_log(folder + "hot.csv", spec)};
  CalibrationOptions options;
  options.model = ModelKind::linear;
  options.smooth_seconds = 1;
  const Calibration calibration = calibrate(logs, spec, options);
  ASSERT_EQ(calibration.model.axes.size(), 3u);
  const auto& x = calibration.model.axes[0];
  EXPECT_EQ(x.name, "column 5");
  const auto& linear = std::get<LinearModel>(x.model);
  ASSERT_EQ(linear.regressors.size(), 2u);
  ASSERT_EQ(linear.regressors[0].name(x.pipeline.term_names()), "dT");
  const double slope_dps_per_c = linear.coefficients(0) / 3600.0;
  EXPECT_GT(slope_dps_per_c, 0.017) << slope_dps_per_c;
  EXPECT_LT(slope_dps_per_c, 0.021) << slope_dps_per_c;
  // The fit removes the bias step between the two temperatures.
  EXPECT_LT(calibration.axes[0].in_sample.mse_after, 0.5 * calibration.axes[0].in_sample.mse_before);
}

}  // namespace
}  // namespace thermodrift
