// fit_warnings: what fit and report must say about a fitted axis.
#include <gtest/gtest.h>

#include <cmath>

#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {
namespace {

ResidualMetrics metrics(double before, double after) {
  ResidualMetrics m;
  m.samples = 100;
  m.mse_before = before;
  m.mse_after = after;
  return m;
}

TEST(FitWarnings, NamesAnUnconvergedSvrAndAModelWorseThanABias) {
  AxisModel axis;
  axis.name = "gyro_x";
  axis.model = LinearModel{};
  EXPECT_TRUE(fit_warnings(axis, metrics(1.0, 0.2)).empty());
  const auto worse = fit_warnings(axis, metrics(1.0, 1.5));
  ASSERT_EQ(worse.size(), 1u);
  EXPECT_NE(worse[0].find("gyro_x: on its own training data the model leaves more drift"), std::string::npos) << worse[0];

  SvrModel svr;
  svr.converged = false;
  axis.model = svr;
  axis.fit.solver = SolverRecord{.iterations = 400000};
  const auto capped = fit_warnings(axis, metrics(1.0, 0.2));
  ASSERT_EQ(capped.size(), 1u);
  EXPECT_NE(capped[0].find("stopped at its iteration cap (400000 steps)"), std::string::npos) << capped[0];
  svr.converged = true;
  axis.model = svr;
  EXPECT_TRUE(fit_warnings(axis, metrics(1.0, 0.2)).empty());
}

// Far from the floor: only the axes above kFarFromFloor, each with its figure; the
// remedy fits what the model already had (its terms searched, more than one log).
TEST(FarFromFloorWarning, NamesOnlyTheAxesAboveItWithTheirFigures) {
  EXPECT_FALSE(far_from_floor_warning({{"x", 1.2}, {"y", kFarFromFloor}}, true, true, 1));
  EXPECT_FALSE(far_from_floor_warning({{"x", std::nan("")}}, true, true, 1));  // no estimate: nothing said

  const auto two = far_from_floor_warning({{"gyro_x", 3.3}, {"gyro_y", 1.1}, {"gyro_z", 250.0}}, true, true, 1);
  ASSERT_TRUE(two);
  EXPECT_EQ(two->rfind("gyro_x, gyro_z: their expected held-out MSEs are 3.3 / 250 × the noise floor estimate", 0), 0u) << *two;
  EXPECT_EQ(two->find("gyro_y"), std::string::npos) << *two;
  EXPECT_EQ(two->find("--features auto"), std::string::npos) << *two;  // searched already
  EXPECT_NE(two->find("another chamber programme in training (--data for each)"), std::string::npos) << *two;

  const auto one = far_from_floor_warning({{"gyro_y", 5.0}}, false, false, 2);
  ASSERT_TRUE(one);
  EXPECT_EQ(one->rfind("gyro_y: on its training data it leaves 5 × the noise floor estimate", 0), 0u) << *one;
  EXPECT_NE(one->find("--features auto, or a further chamber programme"), std::string::npos) << *one;
  EXPECT_EQ(one->find("another chamber programme"), std::string::npos) << *one;  // it had two already
}

}  // namespace
}  // namespace thermodrift
