// A log sampled much faster than the smoothing needs: the feature search reads it as bin
// means of (smoothing window or rate span) / 100 seconds (io/bursts.hpp's binned), while
// the fit of the chosen terms reads every row.
#include <gtest/gtest.h>

#include <vector>

#include "thermodrift/io/bursts.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {
namespace {

// One axis of a one-hour chamber cycle at 20 Hz (-10..40 °C at 3 °C/min).
ChamberLog fast_log() {
  sim::SimulatorOptions options;
  options.cycles = 1;
  options.rate_hz = 20;
  options.chamber_min_c = -10;
  options.chamber_max_c = 40;
  options.ramp_rate_c_per_min = 3;
  options.extreme_soak_min = 10;
  options.start_soak_min = 10;
  ChamberLog log = sim::to_chamber_log(sim::simulate(options));
  log.gyro.resize(1);
  log.gyro_names.resize(1);
  log.temperature.resize(1);
  log.temperature_names.resize(1);
  return log;
}

CalibrationOptions auto_options() {
  CalibrationOptions options;
  options.smooth_seconds = 20;  // bins of 0.2 s: four rows of the 20 Hz log each
  options.terms = {"auto"};
  options.selection.threads = 1;
  return options;
}

TEST(FastLogSearch, TheSearchReadsBinMeansAndTheFitEveryRow) {
  const ChamberLog log = fast_log();
  const CalibrationOptions options = auto_options();
  const auto fast = select_features_per_axis({log}, options);
  const auto bins = select_features_per_axis({binned(log, 0.2)}, options);
  ASSERT_EQ(fast.size(), 1u);
  ASSERT_EQ(bins.size(), 1u);
  EXPECT_EQ(fast[0].terms, bins[0].terms);
  // The same search but for the reference temperature (the mean of every row against the
  // mean of the bin means): 5e-6 apart. (The search on every row of the 20 Hz log chose
  // other terms and scored 3e-3 apart.)
  EXPECT_NEAR(fast[0].cv_mse, bins[0].cv_mse, 1e-4 * bins[0].cv_mse);

  // The fit: the chosen terms, the rows of the 20 Hz log at its own decimation.
  const Calibration calibration = calibrate({log}, LogSpec{}, options);
  const AxisModel& axis = calibration.model.axes.at(0);
  EXPECT_EQ(axis.pipeline.term_names(), fast[0].terms);
  EXPECT_EQ(axis.pipeline.decimation, default_decimation(20, 0.05));
  EXPECT_NE(axis.pipeline.decimation, default_decimation(20, 0.2));
}

}  // namespace
}  // namespace thermodrift
