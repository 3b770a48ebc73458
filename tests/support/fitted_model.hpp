// A drift model fitted on a chamber log without the search or the tuning: shared by the C
// export tests and bench/compensate_bench, which need a real model of a known kind and
// size, quickly.
#pragma once

#include <algorithm>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/models/svr_model.hpp"

namespace thermodrift::testing {

// The paper's pipeline as the tests fit it: 100 s smoothing, 100 s rate span, one row in
// ten, ΔT from `reference_temperature`.
inline Pipeline chamber_pipeline(double reference_temperature = 20) {
  Pipeline pipeline;
  pipeline.smooth_seconds = 100;
  pipeline.rate_span_seconds = 100;
  pipeline.decimation = 10;
  pipeline.reference_temperature = reference_temperature;
  return pipeline;
}

struct FixtureModel {
  // "linear", "svr" (ε-SVR with fixed C = 10, γ = 0.5, ε = 0.05 in standardized units; a
  // few hundred support vectors), "partially_linear" (least squares on the terms, that
  // SVR on its residual) or "linear_part_only" (a partially linear SVR whose kernel fit
  // left out: no support vectors).
  std::string kind = "linear";
  std::vector<std::string> terms;  // empty: the paper's pair (dT, rate)
  // Linear on the paper's pair: its quadratic regressors (to exercise powers), or plain.
  bool squares = true;
  // node_channels[a]: the temperature channel axis a's ΔT is computed from
  // (Pipeline::temperature_channel); missing: the axis' own.
  std::vector<std::optional<std::size_t>> node_channels;
};

// One model per axis of `log`, each fitted on the whole log.
inline DriftModel fitted_model(const ChamberLog& log, const FixtureModel& fixture) {
  DriftModel model;
  model.time_column = "time_s";
  for (std::size_t a = 0; a < log.axes(); ++a) {
    AxisModel axis;
    axis.name = log.gyro_names[a];
    axis.gyro_column = log.gyro_names[a];
    axis.temperature_column = log.temperature_names[a];
    axis.pipeline = chamber_pipeline();
    if (!fixture.terms.empty()) {
      axis.pipeline.terms.clear();
      for (const auto& term : fixture.terms) axis.pipeline.terms.push_back(FeatureTerm::parse(term));
    }
    if (a < fixture.node_channels.size()) axis.pipeline.temperature_channel = fixture.node_channels[a];
    axis.kind = fixture.kind == "linear" ? ModelKind::linear : ModelKind::svr;
    const FeatureTable table = build_feature_table(axis.pipeline, log, a, a, true);
    const std::size_t terms = axis.pipeline.terms.size();
    if (fixture.kind == "linear") {
      axis.model = fit_least_squares(table.features, table.target,
                                     fixture.terms.empty() && fixture.squares ? quadratic_regressors(terms)
                                                                              : linear_regressors(terms));
    } else {
      SvrModel svr;
      Eigen::VectorXd target = table.target;
      if (fixture.kind == "partially_linear" || fixture.kind == "linear_part_only") {
        svr.linear_part = fit_least_squares(table.features, table.target, linear_regressors(terms));
        target -= svr.linear_part->predict(table.features);
      }
      svr.scaling = Standardization::of(table.features, target);
      SvrTrainer trainer(SvrOptions{.C = 10, .gamma = 0.5, .epsilon = 0.05});
      svr.function = trainer.train(svr.scaling.features(table.features), svr.scaling.target(target)).function;
      if (fixture.kind == "linear_part_only") {
        svr.function.support_vectors.resize(0, svr.function.support_vectors.cols());
        svr.function.coefficients.resize(0);
      }
      svr.C = 10;
      svr.epsilon = 0.05;
      axis.model = std::move(svr);
    }
    model.axes.push_back(std::move(axis));
  }
  // Channels after the axes' own, up to the highest a grad term or a node reads.
  std::size_t used = 0;
  for (const auto& axis : model.axes) {
    for (const std::size_t channel : axis.pipeline.channels()) used = std::max(used, channel + 1);
    used = std::max(used, axis.pipeline.temperature_input(0) + 1);
  }
  for (std::size_t c = log.axes(); c < used; ++c) model.extra_temperature_columns.push_back(log.temperature_names[c]);
  return model;
}

}  // namespace thermodrift::testing
