#include "thermodrift/tune/calibration.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <functional>
#include <thread>
#include <algorithm>
#include <cmath>

#include "thermodrift/error.hpp"
#include "thermodrift/io/bursts.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/models/svr_model.hpp"
#include "tune/term_columns.hpp"

namespace thermodrift {

std::vector<std::size_t> temperature_channel_per_axis(const ChamberLog& log) {
  std::vector<std::size_t> channels(log.axes(), 0);
  if (log.temperature.size() == 1) return channels;
  if (log.temperature.size() >= log.axes()) {
    for (std::size_t a = 0; a < channels.size(); ++a) channels[a] = a;
    return channels;
  }
  throw UsageError(fmt::format("{}: {} temperature columns for {} gyro axes; give one for all "
                               "axes or one per axis with --temp (further columns serve grad terms)",
                               log.source, log.temperature.size(), log.axes()));
}

namespace {

// The log's scaling per model input: the axes' temperature columns (log channel
// channels[a]), then the extra channels (log channels axes, axes + 1, ...); a list whose
// values are all equal is kept as one value, so that a log naming one column for all
// axes reads with the model's scaling too.
LogScaling model_scaling(const LogScaling& log, const std::vector<std::size_t>& channels, std::size_t inputs) {
  if (log.is_default()) return {};
  auto per_input = [&](double (LogScaling::*value_of)(std::size_t) const, std::size_t count, bool temperature) {
    std::vector<double> values;
    for (std::size_t i = 0; i < count; ++i) {
      values.push_back((log.*value_of)(temperature && i < channels.size() ? channels[i] : i));
    }
    if (std::all_of(values.begin(), values.end(), [&](double v) { return v == values.front(); })) values.resize(1);
    return values;
  };
  return {per_input(&LogScaling::temperature_scale_of, inputs, true),
          per_input(&LogScaling::temperature_offset_of, inputs, true),
          per_input(&LogScaling::gyro_scale_of, channels.size(), false)};
}

}  // namespace

std::vector<std::string> extra_temperature_columns(const std::vector<ChamberLog>& logs, const LogSpec& spec,
                                                   const std::vector<Pipeline>& pipelines) {
  const ChamberLog& log = logs.front();
  std::size_t used = 0;  // channels up to the highest a grad term or a node reads
  for (const auto& pipeline : pipelines) {
    for (const std::size_t channel : pipeline.channels()) used = std::max(used, channel + 1);
    if (pipeline.temperature_channel) used = std::max(used, *pipeline.temperature_channel + 1);
  }
  if (used == 0) return {};
  if (log.temperature.size() < log.axes()) {
    throw UsageError(fmt::format("grad terms need one temperature column per axis (then any others) with "
                                 "--temp; {} has {} for {} axes",
                                 log.source, log.temperature.size(), log.axes()));
  }
  if (used > log.temperature.size()) {
    throw UsageError(fmt::format("a grad term reads temperature channel {}, but --temp gives {} column(s)", used,
                                 log.temperature.size()));
  }
  std::vector<std::string> extra;
  for (std::size_t c = log.axes(); c < used; ++c) {
    extra.push_back(spec.temperature_columns.empty() ? log.temperature_names[c] : spec.temperature_columns[c]);
  }
  return extra;
}

FeatureTable feature_table(const std::vector<ChamberLog>& logs, const Pipeline& pipeline,
                           std::size_t axis, bool decimate) {
  FeatureTable table;
  for (const auto& log : logs) {
    const auto channels = temperature_channel_per_axis(log);
    append_rows(table, build_feature_table(pipeline, log, axis, channels.at(axis), decimate));
  }
  return table;
}

namespace {

double median_sample_interval(const ChamberLog& log) {
  if (log.rows() < 2) return 1.0;
  std::vector<double> steps;
  const std::size_t stride = std::max<std::size_t>(1, log.rows() / 1000);
  for (std::size_t i = stride; i < log.rows(); i += stride) steps.push_back(log.time[i] - log.time[i - 1]);
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

Pipeline make_pipeline(const std::vector<ChamberLog>& logs, std::size_t axis,
                       const CalibrationOptions& options) {
  Pipeline pipeline;
  pipeline.smooth_seconds = options.smooth_seconds;
  pipeline.rate_span_seconds = options.rate_span_seconds.value_or(std::max(options.smooth_seconds, 1.0));
  pipeline.decimation =
      options.decimation.value_or(default_decimation(options.smooth_seconds, median_sample_interval(logs.front())));
  pipeline.terms.clear();
  // "auto": the paper's pair until select_features replaces it.
  const auto terms = chooses_features(options) ? std::vector<std::string>{"dT", "rate"} : options.terms;
  for (const auto& term : terms) pipeline.terms.push_back(FeatureTerm::parse(term));
  // ΔT is measured from the mean temperature of the training logs.
  double sum = 0;
  std::size_t count = 0;
  for (const auto& log : logs) {
    const auto& channel = log.temperature[temperature_channel_per_axis(log).at(axis)];
    for (double t : channel) sum += t;
    count += channel.size();
  }
  pipeline.reference_temperature = count ? sum / static_cast<double>(count) : 0.0;
  // Trained on burst means: the model keeps their gap threshold, so that compensate,
  // streaming the burst log's rows, carries its state from one burst to the next.
  for (const auto& log : logs) {
    if (log.bursts) pipeline.gap_seconds = std::max(pipeline.effective_gap_seconds(), log.bursts->gap_seconds());
  }
  pipeline.validate();
  return pipeline;
}

void require_samples(const FeatureTable& table, const Pipeline& pipeline, const std::vector<ChamberLog>& logs,
                     std::size_t needed) {
  if (table.rows() >= needed) return;
  double longest = 0;
  for (const auto& log : logs) {
    if (log.rows() > 0) longest = std::max(longest, log.time.back() - log.time.front());
  }
  // A log well past its warm-up that still gives too few samples was thinned by the
  // decimation, which a shorter --smooth would not help.
  const bool thinned = pipeline.decimation > 1 && longest > 2 * pipeline.warm_up_seconds();
  throw DataError(logs.front().source, 0, 0,
                  fmt::format("too little data after the {:g} s warm-up (smoothing {:g} s + rate span "
                              "{:g} s){}: {} usable sample{}, at least {} needed; the longest log spans "
                              "{:g} s ({})",
                              pipeline.warm_up_seconds(), pipeline.smooth_seconds, pipeline.rate_span_seconds,
                              thinned ? fmt::format(" and keeping one ready sample in {}", pipeline.decimation) : "",
                              table.rows(), table.rows() == 1 ? "" : "s", needed, longest,
                              thinned ? "a smaller --decimate helps" : "a shorter --smooth helps"));
}

// The rows of `table` at least `settle_seconds` after the pipeline's (re)start.
FeatureTable settled_rows(const FeatureTable& table, double settle_seconds) {
  std::vector<Eigen::Index> kept;
  FeatureTable out;
  for (std::size_t i = 0, run = 0; i < table.rows(); ++i) {
    for (; run < table.run_start.size() && table.run_start[run] == i; ++run) out.run_start.push_back(kept.size());
    if (table.since_start[i] >= settle_seconds) kept.push_back(static_cast<Eigen::Index>(i));
  }
  out.features = table.features(kept, Eigen::all);
  out.target = table.target(kept);
  for (const Eigen::Index i : kept) {
    const auto k = static_cast<std::size_t>(i);
    out.time.push_back(table.time[k]);
    out.since_start.push_back(table.since_start[k]);
    out.temperature.push_back(table.temperature[k]);
    out.rate.push_back(table.rate[k]);
    out.row.push_back(table.row[k]);
  }
  return out;
}

// The rows of a table streamed over a log with `prepended` rows of history before it
// (with_ramp_history), numbered as the log's own; until the pipeline's first restart (a
// gap), their time since the start counts from the log's first row, `history_seconds` later.
FeatureTable own_rows(const FeatureTable& table, std::size_t prepended, double history_seconds) {
  std::vector<Eigen::Index> kept;
  FeatureTable out;
  out.run_start = {0};
  bool restarted = false;
  for (std::size_t i = 0; i < table.rows(); ++i) {
    restarted = restarted || (i > 0 && table.since_start[i] < table.since_start[i - 1]);
    if (table.row[i] < prepended) continue;
    kept.push_back(static_cast<Eigen::Index>(i));
    out.time.push_back(table.time[i]);
    out.since_start.push_back(restarted ? table.since_start[i] : table.since_start[i] - history_seconds);
    out.temperature.push_back(table.temperature[i]);
    out.rate.push_back(table.rate[i]);
    out.row.push_back(table.row[i] - prepended);
  }
  out.features = table.features(kept, Eigen::all);
  out.target = table.target(kept);
  return out;
}

// The logs the feature search reads: each sampled faster than every (smoothing window or
// rate span, the shorter) / 100 seconds averaged in bins of that width (io/bursts.hpp's
// binned), the others as they are. The search's candidate columns are filters run over
// every row (95 % of the CPU of a 10 Hz log's fit), and what the smoothing leaves of the
// signal does not change within a bin. The fit of the chosen terms reads every row.
std::vector<ChamberLog> logs_for_search(const std::vector<ChamberLog>& logs, const Pipeline& pipeline) {
  const double bin = std::min(pipeline.smooth_seconds, pipeline.rate_span_seconds) / 100;
  std::vector<ChamberLog> out;
  out.reserve(logs.size());
  for (const auto& log : logs) out.push_back(median_sample_interval(log) < 0.5 * bin ? binned(log, bin) : log);
  return out;
}

// The pipeline of the search on `search_logs`: `full`'s (its reference temperature
// included), decimated to the same interval in time as `full` on `logs`.
Pipeline search_pipeline(const Pipeline& full, const std::vector<ChamberLog>& logs,
                         const std::vector<ChamberLog>& search_logs, const CalibrationOptions& options) {
  Pipeline pipeline = full;
  const double interval = median_sample_interval(logs.front());
  const double search_interval = median_sample_interval(search_logs.front());
  if (search_interval == interval) return pipeline;
  pipeline.decimation = options.decimation
                            ? std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(
                                                           static_cast<double>(*options.decimation) * interval /
                                                           search_interval)))
                            : default_decimation(options.smooth_seconds, search_interval);
  return pipeline;
}

// The smallest temperature span (°C, of the smoothed thermometer over the training logs)
// --features auto identifies terms on: a chamber programme spans tens of degrees.
constexpr double kMinIdentifiableSpanC = 1.0;

// The least-squares search of one axis, after the same check of the data a fit makes
// (too short a log says so in terms of the warm-up, not of folds). `logs` are
// logs_for_search's, `pipeline` search_pipeline's.
FeatureSelection search_features(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline,
                                 const CalibrationOptions& calibration) {
  FeatureSelectionOptions options = calibration.selection;  // its own folds, not the tuning's
  options.folds_by = calibration.folds_by;
  options.stop = calibration.stop;
  const FeatureTable table = feature_table(logs, pipeline, axis, true);
  require_samples(table, pipeline, logs, 4 * static_cast<std::size_t>(options.folds));
  // A log whose thermometer hardly moves holds no thermal dynamics: the search then picks
  // columns of almost nothing, and their coefficients (beyond 1e12 on a 999.9 °C soak)
  // made fit fail only at saving, as if the tool had failed.
  const auto [coldest, hottest] = std::minmax_element(table.temperature.begin(), table.temperature.end());
  if (*hottest - *coldest < kMinIdentifiableSpanC) {
    throw DataError(logs.front().source, 0, 0,
                    fmt::format("axis {}: its temperature spans {:.3g} °C ({:.4g} to {:.4g}): --features auto needs a "
                                "log whose temperature moves by at least {:g} °C (a chamber programme); name the "
                                "terms with --features instead",
                                axis + 1, *hottest - *coldest, *coldest, *hottest, kMinIdentifiableSpanC));
  }
  if (calibration.selection_progress) calibration.selection_progress(axis, "choosing feature terms");
  if (options.method == FeatureSelectionOptions::Method::greedy) return select_features(logs, axis, pipeline, options);
  return identify_thermal_node(logs, axis, pipeline, options);
}

// job(axis) for every axis, on up to `threads` threads taking the next axis as each
// finishes; the first axis' exception is rethrown, whatever the thread count.
void for_each_axis(std::size_t axes, int threads, const std::function<void(std::size_t)>& job) {
  std::vector<std::exception_ptr> failures(axes);
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t axis; (axis = next++) < axes;) {
      try {
        job(axis);
      } catch (...) {
        failures[axis] = std::current_exception();
      }
    }
  };
  const std::size_t count = std::clamp<std::size_t>(static_cast<std::size_t>(std::max(1, threads)), 1, std::max<std::size_t>(1, axes));
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < count; ++t) pool.emplace_back(work);
  work();
  for (auto& thread : pool) thread.join();
  for (const auto& failure : failures) {
    if (failure) std::rethrow_exception(failure);
  }
}

}  // namespace

std::vector<FeatureSelection> select_features_per_axis(const std::vector<ChamberLog>& logs,
                                                       const CalibrationOptions& options) {
  if (logs.empty()) throw UsageError("no log to choose features on");
  std::vector<FeatureSelection> selections(logs.front().axes());
  const std::vector<ChamberLog> search_logs = logs_for_search(logs, make_pipeline(logs, 0, options));
  for_each_axis(selections.size(), options.selection.threads, [&](std::size_t axis) {
    const Pipeline pipeline = search_pipeline(make_pipeline(logs, axis, options), logs, search_logs, options);
    selections[axis] = search_features(search_logs, axis, pipeline, options);
  });
  return selections;
}

namespace {

// "blocked 5-fold" or "leave-one-run-out (2 runs)", from a record's folds and folds_by.
std::string cv_name(std::size_t folds, const std::string& folds_by) {
  HeldOutBlocks blocks;
  blocks.blocks.resize(folds);
  blocks.by = parse_folds_by(folds_by);
  return blocks.describe();
}

}  // namespace

std::vector<std::string> fit_warnings(const AxisModel& axis, const ResidualMetrics& in_sample) {
  std::vector<std::string> warnings;
  if (const auto* svr = std::get_if<SvrModel>(&axis.model); svr != nullptr && !svr->converged) {
    warnings.push_back(fmt::format(
        "{}: the SVR stopped at its iteration cap ({} steps) before converging: usable, not optimal; a smaller C "
        "or a looser --tol converges",
        axis.name, axis.fit.solver ? axis.fit.solver->iterations : 0L));
  }
  if (in_sample.samples > 0 && in_sample.mse_after > in_sample.mse_before) {
    warnings.push_back(fmt::format(
        "{}: on its own training data the model leaves more drift than a constant bias correction would (MSE "
        "{:.4g} against {:.4g} (deg/h)^2): do not compensate with it",
        axis.name, in_sample.mse_after, in_sample.mse_before));
  }
  return warnings;
}

std::optional<std::string> far_from_floor_warning(const std::vector<FloorRatio>& axes, bool held_out, bool searched,
                                                  std::size_t training_logs, const std::string& data_option) {
  std::vector<std::string> names;
  std::vector<std::string> ratios;
  for (const auto& axis : axes) {
    if (!(axis.ratio > kFarFromFloor)) continue;
    names.push_back(axis.axis);
    ratios.push_back(fmt::format("{:.3g}", axis.ratio));
  }
  if (names.empty()) return std::nullopt;
  const bool one = names.size() == 1;
  const std::string figure = held_out ? (one ? "its expected held-out MSE is" : "their expected held-out MSEs are")
                                      : (one ? "on its training data it leaves" : "on their training data they leave");
  const std::string remedy = training_logs > 1
                                 ? "a further chamber programme in training, at other rates and over other ranges, helps most"
                                 : fmt::format("another chamber programme in training ({} for each) helps most",
                                               data_option);
  return fmt::format(
      "{}: {} {} × the noise floor estimate: the model does not describe this unit's drift down to the noise, and such models "
      "often miss other programmes by 10 times the floor or more; {}{}",
      fmt::join(names, ", "), figure, fmt::join(ratios, " / "),
      searched ? "" : "--features auto, or ", remedy);
}

std::optional<ExpectedHeldOut> expected_held_out(const FitRecord& fit) {
  if (fit.tuning && fit.tuning->objective == "cv") {
    if (fit.kernel_check) {
      const KernelCheckRecord& check = *fit.kernel_check;
      const std::string nested = cv_name(check.folds, check.folds_by);
      return check.kept ? ExpectedHeldOut{check.with_kernel_mse,
                                          fmt::format("the SVR's nested {} CV, its linear part refitted per fold", nested)}
                        : ExpectedHeldOut{check.linear_part_mse,
                                          fmt::format("the linear part's {} CV; the kernel did not cut it and was left out",
                                                      nested)};
    }
    return ExpectedHeldOut{fit.tuning->objective_mse,
                           fmt::format("the tuned SVR's {} CV", cv_name(fit.tuning->folds, fit.tuning->folds_by))};
  }
  if (fit.feature_selection) {
    const SelectionRecord& selection = *fit.feature_selection;
    return ExpectedHeldOut{selection.cv_mse, fmt::format("the feature search's {} least-squares CV",
                                                         cv_name(selection.folds, selection.folds_by))};
  }
  return std::nullopt;
}

CalibrationOptions calibration_options(const FitRequest& request) {
  const int threads =
      request.threads > 0 ? request.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  CalibrationOptions options;
  options.model = request.model;
  options.smooth_seconds = request.smooth_seconds;
  options.rate_span_seconds = request.rate_span_seconds;
  options.decimation = request.decimation;
  options.terms = request.terms;
  options.selection.method = request.identify;
  options.selection.other_channels = request.other_channels;
  options.selection.power_on_start = request.power_on_start;
  options.selection.threads = threads;
  options.folds_by = request.folds_by;
  options.stop = request.stop;
  if (request.model != ModelKind::svr) return options;
  if (request.sigma && request.gamma) throw UsageError("give --sigma or --gamma, not both (gamma = 1/(2 sigma²))");
  // The paper's method tunes C and σ together; fixed values are used when both are given.
  // One alone, or either beside a tuning method, would be replaced by tuning: refused, not dropped.
  const bool width = request.sigma || request.gamma;
  const char* width_name = request.sigma ? "--sigma" : "--gamma";
  if (request.tune && (request.C || width)) {
    throw UsageError(fmt::format("{} with --tune: tuning chooses C and σ; give --tune, or --C with --sigma (or "
                                 "--gamma) to fix both",
                                 request.C ? "--C" : width_name));
  }
  if (request.C.has_value() != width) {
    throw UsageError(fmt::format("{} alone would be replaced: C and σ are tuned together; give --C with --sigma "
                                 "(or --gamma) to fix both",
                                 request.C ? "--C" : width_name));
  }
  options.svr.C = request.C.value_or(100.0);
  options.svr.gamma = request.gamma ? *request.gamma : gamma_of_sigma(request.sigma.value_or(1.0));
  options.svr.epsilon = request.epsilon;
  options.svr.tolerance = request.tolerance;
  options.svr.approximation = request.approximation;
  options.svr.landmarks = request.landmarks;
  options.max_vectors = request.max_vectors;
  options.keep_kernel = request.keep_kernel;
  if (!request.C) {
    SvrTuningOptions tuning;
    tuning.method = parse_tune_method(request.tune.value_or("afsa"));
    tuning.objective = parse_tune_objective(request.objective);
    tuning.seed = request.seed;
    tuning.threads = threads;
    tuning.evaluations = request.evaluations;
    tuning.folds = request.folds;
    tuning.tune_epsilon = request.tune_epsilon;
    tuning.epsilon = request.epsilon;
    tuning.solver = options.svr;
    std::string why;
    if (!tuning.IsValid(&why)) throw UsageError(why);
    options.tuning = tuning;
  }
  return options;
}

bool chooses_features(const CalibrationOptions& options) {
  return options.terms.size() == 1 && options.terms.front() == "auto";
}

std::size_t minimum_samples(ModelKind model, std::size_t terms) {
  switch (model) {
    case ModelKind::linear: return terms + 2;
    case ModelKind::stepwise: return 2 * terms + 4;
    case ModelKind::svr: return 3;
  }
  return 3;
}

namespace {

// The linear part fitted on the rows outside `block`: least squares on every column, or
// the averaged sets' fits, as the identification averaged them on every row.
LinearModel linear_part_without(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                                const std::vector<std::string>& terms,
                                const std::vector<std::vector<std::string>>& averaged_sets, SampleRange block) {
  const Eigen::MatrixXd x = rows_except(features, block);
  const Eigen::VectorXd y = rows_except(target, block);
  return averaged_sets.empty() ? fit_least_squares(x, y, linear_regressors(terms.size()))
                               : averaged_least_squares(x, y, terms, averaged_sets);
}

// KernelCheckRecord's nested CV over identified.held_out, its MSEs in the standardized
// target's units: in each fold the linear part refitted without the block, the kernel
// (`solver`'s C, γ, ε) trained on that fit's residual outside it, both judged inside.
KernelCheckRecord check_kernel(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                               const std::vector<std::string>& terms, const IdentifiedLinearPart& identified,
                               const Standardization& scaling, const SvrOptions& solver) {
  const Eigen::MatrixXd scaled = scaling.features(features);
  const SvrTrainer trainer(solver);
  const std::vector<std::vector<std::string>> none;
  double with_kernel = 0, without = 0;
  Eigen::Index rows = 0;
  for (const SampleRange& block : identified.held_out.blocks) {
    const LinearModel part =
        linear_part_without(features, target, terms, identified.fit ? identified.averaged_sets : none, block);
    const Eigen::VectorXd residual = scaling.target(target - part.predict(features));
    const SvrFit kernel = trainer.train(rows_except(scaled, block), rows_except(residual, block));
    const Eigen::VectorXd held = residual.segment(block.begin, block.size());
    with_kernel += (held - kernel.function.predict(scaled.middleRows(block.begin, block.size()))).squaredNorm();
    without += held.squaredNorm();
    rows += block.size();
  }
  KernelCheckRecord check;
  check.folds = identified.held_out.blocks.size();
  check.folds_by = to_string(identified.held_out.by);
  check.with_kernel_mse = with_kernel / static_cast<double>(rows);
  check.linear_part_mse = without / static_cast<double>(rows);
  return check;
}

}  // namespace

FittedModel fit_model(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                      const std::vector<std::string>& terms, const CalibrationOptions& options,
                      bool standardize, std::size_t axis, const IdentifiedLinearPart* identified) {
  const LinearModel* linear_fit = identified && identified->fit ? &*identified->fit : nullptr;
  FittedModel fitted;
  fitted.fit.terms = terms;
  fitted.fit.averaged_linear_part = linear_fit != nullptr && options.model != ModelKind::stepwise;
  if (options.model == ModelKind::linear) {
    fitted.model = linear_fit ? *linear_fit : fit_least_squares(features, target, linear_regressors(terms.size()));
  } else if (options.model == ModelKind::stepwise) {
    StepwiseOptions stepwise_options;
    stepwise_options.stop = options.stop;
    auto stepwise = fit_stepwise(features, target,
                                 options.partially_linear ? linear_regressors(terms.size())
                                                          : quadratic_regressors(terms.size()),
                                 terms, stepwise_options);
    for (const auto& step : stepwise.path) fitted.fit.stepwise_path.push_back({step.action, step.regressor, step.f_statistic});
    fitted.model = std::move(stepwise.model);
  } else if (options.model == ModelKind::svr) {
    SvrModel svr;
    Eigen::VectorXd kernel_target = target;
    if (options.partially_linear) {
      svr.linear_part = linear_fit ? *linear_fit
                                   : fit_least_squares(features, target,
                                                       linear_regressors(static_cast<std::size_t>(features.cols())));
      kernel_target -= svr.linear_part->predict(features);
      fitted.fit.partially_linear = true;
    }
    svr.scaling = standardize ? Standardization::of(features, kernel_target)
                              : Standardization::identity(features.cols());
    const Eigen::MatrixXd scaled_features = svr.scaling.features(features);
    const Eigen::VectorXd scaled_target = svr.scaling.target(kernel_target);
    SvrOptions solver = options.svr;
    solver.stop = options.stop;
    long evaluations = 1;
    bool kernel_kept = true;
    if (options.tuning) {
      SvrTuningOptions tuning = *options.tuning;
      tuning.solver.stop = options.stop;
      if (options.tuning_progress) {
        tuning.progress = [&](const optim::Progress& progress) { return options.tuning_progress(axis, progress); };
      }
      const SvrTuningResult tuned = tune_svr(scaled_features, scaled_target, tuning);
      if (tuned.termination == optim::Termination::stopped_by_callback) throw Interrupted("tuning stopped");
      solver = tuned.solver;
      fitted.tuning_seconds = tuned.seconds;
      evaluations = tuned.evaluations;
      const auto in_dph2 = [scale = svr.scaling.target_scale](double value) { return value * scale * scale; };  // (°/h)²
      TuningRecord record;
      record.method = to_string(tuning.method);
      record.objective = to_string(tuned.objective);
      record.optimistic = tuned.optimistic;
      record.folds = tuning.blocks.empty() ? static_cast<std::size_t>(tuning.folds) : tuning.blocks.size();
      record.folds_by = tuning.blocks.empty() ? "time" : "runs";
      record.objective_mse = in_dph2(tuned.objective_value);
      record.fits = tuned.fits;
      record.capped_fits = tuned.capped_fits;
      record.seed = tuning.seed;
      record.C_box = {tuning.C_min, tuning.C_max};
      record.sigma_box = {tuning.sigma_min, tuning.sigma_max};
      if (tuning.tune_epsilon) record.epsilon_box = std::array<double, 2>{tuning.epsilon_min, tuning.epsilon_max};
      record.epsilon = tuning.epsilon;
      for (const auto& point : tuned.history) record.history.push_back({point.evaluations, in_dph2(point.best_value)});
      fitted.fit.tuning = std::move(record);
      const bool judged = options.partially_linear && !options.keep_kernel;
      if (judged && identified && identified->held_out.blocks.size() >= 2) {
        if (options.selection_progress) {
          options.selection_progress(axis, fmt::format("tuned; judging the kernel by nested {}-fold CV",
                                                       identified->held_out.blocks.size()));
        }
        KernelCheckRecord check = check_kernel(features, target, terms, *identified, svr.scaling, solver);
        check.with_kernel_mse = in_dph2(check.with_kernel_mse);
        check.linear_part_mse = in_dph2(check.linear_part_mse);
        check.min_gain = options.selection.min_gain;
        check.kept = check.with_kernel_mse < (1.0 - check.min_gain) * check.linear_part_mse;
        kernel_kept = check.kept;
        fitted.fit.kernel_check = std::move(check);
      }
    }
    SvrFit result;
    if (kernel_kept) {
      const SvrTrainer trainer(solver);
      result = trainer.train(scaled_features, scaled_target);
    } else {
      // The linear part alone: a kernel sum without vectors and a bias of 0, so each
      // prediction is the linear part plus the residual's mean (the target scaling's).
      result.function.support_vectors.resize(0, features.cols());
      result.function.gamma = solver.gamma;
      result.summary.support_vectors = 0;
    }
    svr.function = result.function;
    if (options.max_vectors && static_cast<std::size_t>(svr.function.support_vectors.rows()) > *options.max_vectors) {
      const auto in_sample_mse = [&] {
        const double scale = svr.scaling.target_scale;
        return (scaled_target - svr.function.predict(scaled_features)).squaredNorm() /
               static_cast<double>(scaled_target.size()) * scale * scale;
      };
      const double before = in_sample_mse();
      ReduceOptions reduce;
      reduce.max_vectors = *options.max_vectors;
      reduce.stop = options.stop;
      CompressionRecord record = compress(svr, scaled_features, reduce);
      record.training_mse_before = before;
      record.training_mse_after = in_sample_mse();
      fitted.fit.compressed = std::move(record);
    }
    svr.C = solver.C;
    svr.epsilon = solver.epsilon;
    svr.converged = result.summary.termination == SvrTermination::converged;
    fitted.fit.params = SvrParameters{svr.C, svr.sigma(), svr.function.gamma, svr.epsilon};
    fitted.fit.standardized = standardize;
    SolverRecord solver_record;
    solver_record.termination = kernel_kept ? to_string(result.summary.termination) : "not trained: kernel left out";
    solver_record.iterations = result.summary.iterations;
    solver_record.support_vectors = result.summary.support_vectors;
    solver_record.dual_objective = result.summary.dual_objective;
    solver_record.kernel = to_string(result.summary.approximation);
    if (result.summary.approximation == SvrApproximation::nystrom ||
        result.summary.approximation == SvrApproximation::low_rank) {
      // The factor and what it cost, for whoever reads the model: its rank (the landmarks
      // are the support vectors) and the kernel it leaves unexplained (low rank: none that
      // counts, the fit is the exact one).
      solver_record.landmarks = result.summary.landmarks;
      solver_record.mean_kernel_residual = result.summary.kernel_residual;
      solver_record.samples_outside_tube = result.summary.support_vectors;
    }
    fitted.fit.solver = std::move(solver_record);
    fitted.fit.evaluations = evaluations;
    fitted.model = std::move(svr);
  }
  return fitted;
}

Calibration calibrate_libsvm(const LabelledData& data, const std::string& source,
                             const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto columns = static_cast<std::size_t>(data.samples.cols());
  if (static_cast<std::size_t>(data.samples.rows()) < minimum_samples(options.model, columns)) {
    throw DataError(source, 0, 0, fmt::format("{} samples are too few for a {} model", data.samples.rows(), to_string(options.model)));
  }
  AxisModel axis;
  axis.name = "label";
  axis.gyro_column = "label";
  axis.temperature_column = "";
  axis.pipeline = Pipeline::libsvm_input(columns);
  axis.kind = options.model;
  FittedModel fitted = fit_model(data.samples, data.targets, axis.pipeline.term_names(), options, false);
  axis.model = std::move(fitted.model);
  AxisCalibration report;
  report.in_sample = residual_metrics(data.targets, axis.predict(data.samples));
  report.training_samples = static_cast<std::size_t>(data.samples.rows());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fitted.fit.training_samples = report.training_samples;
  fitted.fit.in_sample = report.in_sample;
  axis.fit = std::move(fitted.fit);
  Calibration calibration;
  calibration.model.axes.push_back(std::move(axis));
  calibration.axes.push_back(report);
  return calibration;
}

ResidualMetrics evaluate_libsvm(const DriftModel& model, const LabelledData& data, const std::string& source) {
  if (model.axes.size() != 1 || !model.axes.front().pipeline.libsvm) {
    throw UsageError("--format libsvm needs a model fitted with --format libsvm");
  }
  const auto& axis = model.axes.front();
  if (static_cast<std::size_t>(data.samples.cols()) > axis.pipeline.terms.size()) {
    throw DataError(source, 0, 0, fmt::format("the data has {} features, the model {}", data.samples.cols(),
                                              axis.pipeline.terms.size()));
  }
  // libsvm's sparse format omits trailing zero features: pad to the model's width.
  Eigen::MatrixXd samples = Eigen::MatrixXd::Zero(data.samples.rows(), static_cast<Eigen::Index>(axis.pipeline.terms.size()));
  samples.leftCols(data.samples.cols()) = data.samples;
  return residual_metrics(data.targets, axis.predict(samples));
}

Calibration calibrate(const std::vector<ChamberLog>& logs, const LogSpec& spec,
                      const CalibrationOptions& options) {
  if (logs.empty()) throw UsageError("no log to calibrate on");
  const auto& first = logs.front();
  for (const auto& log : logs) {
    if (log.axes() != first.axes() || log.temperature.size() != first.temperature.size()) {
      throw UsageError(fmt::format("{} and {} have different numbers of gyro or temperature columns",
                                   first.source, log.source));
    }
  }
  Calibration calibration;
  calibration.model.gyro_unit = spec.gyro_unit;
  calibration.model.time_column = spec.time_column;
  calibration.model.time_unit = spec.time_unit;
  calibration.model.despike = spec.despike;
  if (spec.despike) {  // counts of the training logs: per axis' gyro, per temperature channel
    calibration.model.despiked_gyro.assign(first.axes(), 0);
    calibration.model.despiked_temperature.assign(first.temperature.size(), 0);
    for (const auto& log : logs) {
      for (std::size_t a = 0; a < log.despiked_gyro.size() && a < first.axes(); ++a) {
        calibration.model.despiked_gyro[a] += log.despiked_gyro[a];
      }
      for (std::size_t c = 0; c < log.despiked_temperature.size() && c < first.temperature.size(); ++c) {
        calibration.model.despiked_temperature[c] += log.despiked_temperature[c];
      }
    }
  }
  calibration.model.rate_hz = spec.rate_hz;
  const auto channels = temperature_channel_per_axis(first);

  const std::vector<FeatureSelection>& searched = options.selections;  // given ones, if any
  std::vector<ChamberLog> search_logs;
  if (chooses_features(options) && searched.size() < first.axes()) {
    search_logs = logs_for_search(logs, make_pipeline(logs, 0, options));
  }
  // Each axis' terms, fit and tuning, the axes in parallel like the searches: one axis'
  // SVR tuning runs while another's search or tuning still does. Each axis' result does
  // not depend on the thread count; they are put in order.
  const std::size_t axes = first.axes();
  std::vector<AxisModel> axis_models(axes);
  std::vector<AxisCalibration> axis_reports(axes);
  auto fit_axis = [&](std::size_t axis) {
    options.stop.throw_if_requested("calibration");
    const auto start = std::chrono::steady_clock::now();
    AxisModel axis_model;
    axis_model.name = first.gyro_names[axis];
    axis_model.gyro_column = spec.gyro_columns.empty() ? first.gyro_names[axis] : spec.gyro_columns[axis];
    const auto channel = channels[axis];
    axis_model.temperature_column = spec.temperature_columns.empty()
                                        ? first.temperature_names[channel]
                                        : spec.temperature_columns[channel];
    axis_model.pipeline = make_pipeline(logs, axis, options);
    axis_model.kind = options.model;
    std::optional<SelectionRecord> selection_record;
    IdentifiedLinearPart identified;
    if (chooses_features(options)) {
      const FeatureSelectionOptions& selection_options = options.selection;
      FeatureSelection selection =
          axis < searched.size()
              ? searched[axis]
              : search_features(search_logs, axis, search_pipeline(axis_model.pipeline, logs, search_logs, options),
                                options);
      if (options.model == ModelKind::svr && selection_options.method == FeatureSelectionOptions::Method::greedy) {
        if (options.selection_progress) options.selection_progress(axis, "judging the chosen terms by SVR");
        SvrJudgeOptions judge;
        judge.tuning = options.tuning;
        if (judge.tuning) judge.tuning->solver.stop = options.stop;
        judge.fixed = options.svr;
        judge.fixed.stop = options.stop;
        if (options.tuning) judge.folds = options.tuning->folds;
        judge.folds_by = options.folds_by;
        judge.min_gain = selection_options.min_gain;
        judge_by_svr(selection, logs, axis, axis_model.pipeline, judge);
      }
      axis_model.pipeline.terms.clear();
      for (const auto& term : selection.terms) axis_model.pipeline.terms.push_back(FeatureTerm::parse(term));
      axis_model.pipeline.temperature_channel = selection.temperature_channel;
      axis_model.pipeline.validate();
      selection_record = selection.record(selection_options);
      identified.fit = std::move(selection.linear_fit);
      identified.averaged_sets = std::move(selection.averaged_sets);
    }
    const auto& pipeline = axis_model.pipeline;

    const FeatureTable training = feature_table(logs, pipeline, axis, true);
    require_samples(training, pipeline, logs, minimum_samples(options.model, pipeline.terms.size()));
    CalibrationOptions axis_options = options;
    axis_options.partially_linear = options.partially_linear ||
                                    (chooses_features(options) &&
                                     options.selection.method == FeatureSelectionOptions::Method::thermal_node);
    if (axis_options.tuning && axis_options.tuning->objective == TuneObjective::cv) {
      const HeldOutBlocks held_out = cv_blocks(training.features.rows(), training.run_start,
                                               axis_options.tuning->folds, options.folds_by);
      if (held_out.by == FoldsBy::runs) axis_options.tuning->blocks = held_out.blocks;
    }
    // The blocks of the kernel check.
    if (axis_options.partially_linear && options.model == ModelKind::svr && !options.keep_kernel) {
      identified.held_out = cv_blocks(training.features.rows(), training.run_start, options.selection.folds,
                                      options.folds_by);
    }
    FittedModel fitted =
        fit_model(training.features, training.target, pipeline.term_names(), axis_options, true, axis, &identified);
    axis_model.model = std::move(fitted.model);
    FitRecord fit = std::move(fitted.fit);
    fit.feature_selection = std::move(selection_record);

    AxisCalibration report;
    const FeatureTable every = feature_table(logs, pipeline, axis, false);
    report.in_sample = residual_metrics(every.target, axis_model.predict(every.features));
    axis_model.envelope = TrainingEnvelope::of(every);
    report.training_samples = training.rows();
    report.tuning_seconds = fitted.tuning_seconds;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fit.training_samples = report.training_samples;
    fit.in_sample = report.in_sample;
    axis_model.fit = std::move(fit);
    axis_models[axis] = std::move(axis_model);
    axis_reports[axis] = report;
  };
  for_each_axis(axes, options.selection.threads, fit_axis);
  calibration.model.axes = std::move(axis_models);
  calibration.axes = std::move(axis_reports);
  std::vector<Pipeline> pipelines;
  for (const auto& axis : calibration.model.axes) pipelines.push_back(axis.pipeline);
  calibration.model.extra_temperature_columns = extra_temperature_columns(logs, spec, pipelines);
  calibration.model.scaling = model_scaling(spec.scaling, channels, calibration.model.temperature_inputs());
  return calibration;
}

std::vector<ResidualMetrics> evaluate_from(const DriftModel& model, const ChamberLog& log, std::size_t first_row) {
  if (log.axes() != model.axes.size()) {
    throw DataError(log.source, 0, 0,
                    fmt::format("the model has {} axes but {} gyro columns were read", model.axes.size(), log.axes()));
  }
  std::vector<ResidualMetrics> metrics;
  for (std::size_t axis = 0; axis < model.axes.size(); ++axis) {
    const auto& axis_model = model.axes[axis];
    const auto channel = temperature_channel_per_axis(log).at(axis);
    const FeatureTable table = build_feature_table(axis_model.pipeline, log, axis, channel, false);
    const auto first = static_cast<Eigen::Index>(
        std::lower_bound(table.row.begin(), table.row.end(), first_row) - table.row.begin());
    const Eigen::Index count = static_cast<Eigen::Index>(table.rows()) - first;
    if (count <= 0) {
      throw DataError(log.source, 0, 0, fmt::format("no usable samples from row {} on", first_row + 1));
    }
    metrics.push_back(residual_metrics(table.target.tail(count),
                                       axis_model.predict(table.features.bottomRows(count))));
  }
  return metrics;
}

std::vector<ResidualMetrics> evaluate(const DriftModel& model, const std::vector<ChamberLog>& logs,
                                      double settle_seconds) {
  std::vector<ResidualMetrics> metrics;
  for (const auto& axis : evaluate_axes(model, logs, settle_seconds)) metrics.push_back(axis.metrics);
  return metrics;
}

namespace {

// An axis model's prediction of a table's rows, in blocks, so that a stop request is seen
// during an SVR's prediction of a long log.
Eigen::VectorXd predict_rows(const AxisModel& axis_model, const Eigen::MatrixXd& features, const StopToken& stop) {
  constexpr Eigen::Index kBlock = 4096;
  Eigen::VectorXd predicted(features.rows());
  for (Eigen::Index begin = 0; begin < features.rows(); begin += kBlock) {
    stop.throw_if_requested("evaluation");
    const Eigen::Index count = std::min(kBlock, features.rows() - begin);
    predicted.segment(begin, count) = axis_model.predict(features.middleRows(begin, count));
  }
  return predicted;
}

// LogStart::estimated on one log: power-on's prediction of `on`'s rows moved by w times the
// running start's difference from it (`running`: the table after the ramp history, its
// rows the log's own), w fitted on the rows before `settle_seconds`. Returns w.
double blend_starts(const AxisModel& axis_model, const FeatureTable& on, const FeatureTable& running,
                    double settle_seconds, const StopToken& stop, Eigen::VectorXd& predicted) {
  predicted = predict_rows(axis_model, on.features, stop);
  const Eigen::VectorXd other = predict_rows(axis_model, running.features, stop);
  Eigen::VectorXd difference = Eigen::VectorXd::Zero(predicted.size());
  for (std::size_t i = 0, j = 0; i < on.rows(); ++i) {
    while (j < running.rows() && running.row[j] < on.row[i]) ++j;
    if (j < running.rows() && running.row[j] == on.row[i]) {
      const double value = other[static_cast<Eigen::Index>(j)] - predicted[static_cast<Eigen::Index>(i)];
      // A start whose prediction overflows says nothing; power-on's own stays as it is.
      if (std::isfinite(value)) difference[static_cast<Eigen::Index>(i)] = value;
    }
  }
  double cross = 0, square = 0;
  for (std::size_t i = 0; i < on.rows() && on.since_start[i] < settle_seconds; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    cross += difference[k] * (on.target[k] - predicted[k]);
    square += difference[k] * difference[k];
  }
  const double weight = square > 0 && std::isfinite(cross / square) ? std::clamp(cross / square, 0.0, 1.0) : 0.0;
  predicted += weight * difference;
  return weight;
}

}  // namespace

LogStart parse_log_start(const std::string& name) {
  if (name == "power-on") return LogStart::power_on;
  if (name == "running") return LogStart::running;
  if (name == "estimated") return LogStart::estimated;
  throw UsageError(fmt::format("log start '{}' is not power-on, running or estimated", name));
}

std::string log_start_name(LogStart start) {
  switch (start) {
    case LogStart::power_on: return "power-on";
    case LogStart::running: return "running";
    case LogStart::estimated: return "estimated";
  }
  return {};
}

std::vector<AxisEvaluation> evaluate_axes(const DriftModel& model, const std::vector<ChamberLog>& logs,
                                          double settle_seconds, const StopToken& stop, LogStart start) {
  // Without settling rows the estimated start is power-on (w = 0): no history to stream.
  const bool blend = start == LogStart::estimated && settle_seconds > 0;
  std::vector<ChamberLog> histories;  // LogStart::running and a blend: each log after its ramp history
  if (start == LogStart::running || blend) {
    for (const auto& log : logs) histories.push_back(with_ramp_history(log));
  }
  std::vector<AxisEvaluation> evaluations;
  for (std::size_t axis = 0; axis < model.axes.size(); ++axis) {
    const auto& axis_model = model.axes[axis];
    AxisEvaluation evaluation;
    FeatureTable table;
    std::vector<double> predicted;
    for (std::size_t l = 0; l < logs.size(); ++l) {
      const ChamberLog& log = logs[l];
      stop.throw_if_requested("evaluation");
      if (log.axes() != model.axes.size()) {
        throw DataError(log.source, 0, 0,
                        fmt::format("the model has {} axes but {} gyro columns were read",
                                    model.axes.size(), log.axes()));
      }
      const auto channel = temperature_channel_per_axis(log).at(axis);
      const auto after_history = [&] {
        return own_rows(build_feature_table(axis_model.pipeline, histories[l], axis, channel, false),
                        histories[l].rows() - log.rows(), log.time.front() - histories[l].time.front());
      };
      FeatureTable part;
      Eigen::VectorXd part_predicted;
      double settle = settle_seconds;
      if (start == LogStart::running) {
        part = after_history();
        // After a history the first rows are ready, but their smoothed gyro still averages the
        // history's made-up one: the log's own warm-up stays out, as without it.
        settle = std::max(settle_seconds, axis_model.pipeline.warm_up_seconds());
        part_predicted = predict_rows(axis_model, part.features, stop);
      } else {
        part = build_feature_table(axis_model.pipeline, log, axis, channel, false);
        if (blend) {
          evaluation.running_weight.push_back(
              blend_starts(axis_model, part, after_history(), settle_seconds, stop, part_predicted));
        } else {
          if (start == LogStart::estimated) evaluation.running_weight.push_back(0.0);
          part_predicted = predict_rows(axis_model, part.features, stop);
        }
      }
      for (std::size_t i = 0; i < part.rows(); ++i) {
        if (!(part.since_start[i] < settle)) predicted.push_back(part_predicted[static_cast<Eigen::Index>(i)]);
      }
      if (settle > 0) part = settled_rows(part, settle);
      append_rows(table, part);
    }
    if (table.rows() == 0) {
      throw DataError(logs.front().source, 0, 0,
                      fmt::format("no usable samples after the {:g} s warm-up{}", axis_model.pipeline.warm_up_seconds(),
                                  settle_seconds > 0 ? fmt::format(" and {:g} s of settling", settle_seconds) : ""));
    }
    evaluation.metrics =
        residual_metrics(table.target, Eigen::Map<const Eigen::VectorXd>(predicted.data(), static_cast<Eigen::Index>(predicted.size())));
    evaluation.rows = table.row;
    evaluation.predicted = std::move(predicted);
    if (axis_model.envelope) evaluation.outside_envelope = tally_outside(*axis_model.envelope, table);
    evaluations.push_back(std::move(evaluation));
  }
  return evaluations;
}

}  // namespace thermodrift
