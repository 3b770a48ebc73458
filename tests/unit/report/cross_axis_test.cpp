// The cross-axis experiment fits each pooled SVR with the left-out axis' own C, γ, ε:
// the self-regression's tuning is not run again (docs/report.md).
#include <gtest/gtest.h>

#include <variant>

#include "thermodrift/report/cross_axis.hpp"
#include "thermodrift/sim/chamber_run.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift {
namespace {

TEST(CrossAxis, FitsWithTheLeftOutAxisHyperParametersUntuned) {
  sim::SimulatorOptions simulator;
  simulator.rate_hz = 0.1;
  const ChamberLog log = sim::to_chamber_log(sim::simulate(simulator));
  const std::size_t split = log.rows() / 2;
  const ChamberLog training = slice_rows(log, 0, split);
  const ChamberLog held_out = slice_rows(log, split, log.rows());
  LogSpec spec;
  CalibrationOptions options;
  options.model = ModelKind::svr;
  SvrTuningOptions tuning;
  tuning.evaluations = 8;
  options.tuning = tuning;
  const DriftModel fitted = calibrate({training}, spec, options).model;

  const auto results = run_cross_axis(training, held_out, log, fitted, options);
  ASSERT_EQ(results.size(), fitted.axes.size());
  for (const auto& result : results) {
    const auto& own = std::get<SvrModel>(fitted.axes[result.left_out].model);
    const auto& pooled = std::get<SvrModel>(result.model.model);
    EXPECT_EQ(pooled.C, own.C) << result.left_out_name;
    EXPECT_EQ(pooled.function.gamma, own.function.gamma) << result.left_out_name;
    EXPECT_EQ(pooled.epsilon, own.epsilon) << result.left_out_name;
    EXPECT_FALSE(result.model.fit.tuning.has_value()) << result.left_out_name;
    EXPECT_EQ(result.model.fit.evaluations, std::optional<long>(1)) << result.left_out_name;
  }
}

}  // namespace
}  // namespace thermodrift
