// evaluate_axes hands back the rows it judged and its prediction of them, the ones its
// metrics were computed from, from whichever log start it was asked for: a caller that
// judges the prediction otherwise (against the simulator's true drift) judges the same.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <vector>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {
namespace {

TEST(Evaluate, GivesTheJudgedRowsAndTheirPredictionForEveryLogStart) {
  sim::SimulatorOptions simulated;
  simulated.rate_hz = 0.2;
  const sim::ChamberRun run = sim::simulate(simulated);
  const ChamberLog log = sim::to_chamber_log(run);
  const std::size_t split = run.cycle_start_rows().at(1);
  const ChamberLog first = slice_rows(log, 0, split), second = slice_rows(log, split, log.rows());
  CalibrationOptions options;
  options.model = ModelKind::linear;
  options.terms = {"dT", "lag:600", "lagrate:600", "on:600"};
  const DriftModel model = calibrate({first}, LogSpec{}, options).model;
  const double settle = 1800;
  for (const LogStart start : {LogStart::power_on, LogStart::running, LogStart::estimated}) {
    SCOPED_TRACE(log_start_name(start));
    const auto evaluations = evaluate_axes(model, {first, second}, settle, {}, start);
    ASSERT_EQ(evaluations.size(), 3u);
    for (std::size_t a = 0; a < 3; ++a) {
      const AxisEvaluation& axis = evaluations[a];
      ASSERT_EQ(axis.rows.size(), axis.metrics.samples);
      ASSERT_EQ(axis.predicted.size(), axis.metrics.samples);
      // Each log's own rows, in order, the second log's counting from its own start again.
      const auto restart = std::is_sorted_until(axis.rows.begin(), axis.rows.end());
      ASSERT_NE(restart, axis.rows.end());
      EXPECT_TRUE(std::is_sorted(restart, axis.rows.end()));
      // The metrics are those of this prediction against the smoothed gyro of these rows.
      double squares = 0;
      std::size_t i = 0;
      for (const ChamberLog* part : {&first, &second}) {
        const FeatureTable table = build_feature_table(model.axes[a].pipeline, *part, a, a, false);
        for (std::size_t r = 0; r < table.rows() && i < axis.rows.size(); ++r) {
          if (table.row[r] != axis.rows[i]) continue;
          const double residual = table.target[static_cast<Eigen::Index>(r)] - axis.predicted[i++];
          squares += residual * residual;
        }
      }
      ASSERT_EQ(i, axis.rows.size()) << "a judged row the log does not have";
      EXPECT_NEAR(squares / static_cast<double>(i), axis.metrics.mse_after, 1e-9 * axis.metrics.mse_after);
    }
  }
  // Power-on's prediction is the model's on the log's own table.
  const auto power_on = evaluate_axes(model, {second}, settle, {}, LogStart::power_on);
  const FeatureTable table = build_feature_table(model.axes[0].pipeline, second, 0, 0, false);
  const Eigen::VectorXd direct = model.axes[0].predict(table.features);
  const auto first_judged = static_cast<Eigen::Index>(
      std::find(table.row.begin(), table.row.end(), power_on[0].rows.front()) - table.row.begin());
  for (std::size_t i = 0; i < power_on[0].rows.size(); i += 97) {
    EXPECT_EQ(power_on[0].predicted[i], direct[first_judged + static_cast<Eigen::Index>(i)]);
  }
}

}  // namespace
}  // namespace thermodrift
