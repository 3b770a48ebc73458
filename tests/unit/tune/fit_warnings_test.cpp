// fit_warnings: what fit and report must say about a fitted axis.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace thermodrift
