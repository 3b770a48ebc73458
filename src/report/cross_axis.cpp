#include "thermodrift/report/cross_axis.hpp"

#include <algorithm>
#include <chrono>
#include <variant>

#include "thermodrift/error.hpp"

namespace thermodrift {

std::vector<CrossAxisResult> run_cross_axis(const ChamberLog& training, const ChamberLog& held_out,
                                            const ChamberLog& whole, const DriftModel& fitted,
                                            const CalibrationOptions& options) {
  std::vector<CrossAxisResult> results;
  const std::size_t axes = fitted.axes.size();
  if (axes < 2) return results;
  const std::vector<ChamberLog> training_logs{training};
  for (std::size_t left_out = 0; left_out < axes; ++left_out) {
    options.stop.throw_if_requested("cross-axis experiment");  // and every fit below
    const auto start = std::chrono::steady_clock::now();
    CrossAxisResult result;
    result.left_out = left_out;
    result.left_out_name = fitted.axes[left_out].name;
    FeatureTable pooled;
    for (std::size_t axis = 0; axis < axes; ++axis) {
      if (axis == left_out) continue;
      result.training_axes.push_back(fitted.axes[axis].name);
      append_rows(pooled, feature_table(training_logs, fitted.axes[axis].pipeline, axis, true));
    }
    // The same hyper-parameters as the left-out axis's own SVR (tuned or fixed), used as
    // they are, not tuned again: the only difference from self-regression is the data.
    CalibrationOptions svr_options = options;
    svr_options.model = ModelKind::svr;
    if (const auto* own = std::get_if<SvrModel>(&fitted.axes[left_out].model)) {
      svr_options.svr.C = own->C;
      svr_options.svr.gamma = own->function.gamma;
      svr_options.svr.epsilon = own->epsilon;
      svr_options.partially_linear = own->linear_part.has_value();
      svr_options.tuning.reset();
    }
    // Tuned (large C, small σ) points can take SMO long on the pooled samples, which hold
    // two drift laws; the experiment only needs to show that one model does not fit both,
    // so the fit is capped (20k SMO steps, tolerance 1e-2; the termination is recorded in `fit`).
    svr_options.svr.max_iterations = std::min<long>(svr_options.svr.max_iterations, 20'000);
    svr_options.svr.tolerance = std::max(svr_options.svr.tolerance, 1e-2);
    const auto& pipeline = fitted.axes[left_out].pipeline;
    FittedModel model = fit_model(pooled.features, pooled.target, pipeline.term_names(), svr_options, true);
    result.model = fitted.axes[left_out];
    result.model.kind = ModelKind::svr;
    result.model.model = std::move(model.model);
    result.model.fit = std::move(model.fit);
    result.training_samples = pooled.rows();

    const auto metrics_on = [&](const ChamberLog& log) {
      const FeatureTable table = feature_table({log}, pipeline, left_out, false);
      if (table.rows() == 0) throw DataError(log.source, 0, 0, "no usable samples for the cross-axis test");
      return residual_metrics(table.target, result.model.predict(table.features));
    };
    result.held_out = metrics_on(held_out);
    result.whole_log = metrics_on(whole);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    results.push_back(std::move(result));
  }
  return results;
}

}  // namespace thermodrift
