#include "thermodrift/report/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "report_parts.hpp"
#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/features/moving_average.hpp"
#include "thermodrift/features/noise_floor.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/report/allan.hpp"
#include "thermodrift/report/cross_axis.hpp"

namespace thermodrift {

std::string format_number(double value) {
  if (!std::isfinite(value)) return "–";
  return fmt::format("{:.4g}", value);
}

std::string kernel_check_text(const nlohmann::json& check) {
  const double with_kernel = check.at("with_kernel_mse").get<double>();
  const double linear = check.at("linear_part_mse").get<double>();
  const std::string cv = fmt::format("nested {}-fold CV", check.at("folds").get<std::size_t>());
  if (check.at("kept").get<bool>()) {
    return fmt::format("kept: {} MSE {} (°/h)² against the linear part's {}", cv, format_number(with_kernel),
                       format_number(linear));
  }
  return fmt::format("left out: {} MSE {} (°/h)² against the linear part's {}, not {:g} % lower; the model is its "
                     "linear part",
                     cv, format_number(with_kernel), format_number(linear), 100 * check.at("min_gain").get<double>());
}

namespace {

using namespace report_detail;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The drift a Compensator of `model`, run over the whole of `log`, subtracts from its rows
// from `first` on, per axis (a log with one temperature column feeds it to every axis, as
// compensate does).
std::vector<std::vector<double>> compensator_drift(const DriftModel& model, const ChamberLog& log, std::size_t first) {
  Compensator compensator(model);
  const std::size_t inputs = model.temperature_inputs();
  const bool shared = log.temperature.size() == 1;
  std::vector<std::vector<double>> drift(model.axes.size(), std::vector<double>(log.rows() - std::min(first, log.rows())));
  std::vector<double> gyro(model.axes.size()), temperatures(inputs);
  for (std::size_t i = 0; i < log.rows(); ++i) {
    for (std::size_t a = 0; a < gyro.size(); ++a) gyro[a] = log.gyro[a][i];
    for (std::size_t c = 0; c < inputs; ++c) temperatures[c] = log.temperature[shared ? 0 : c][i];
    const auto& out = compensator.push(log.time[i], gyro, temperatures);
    if (i < first) continue;
    for (std::size_t a = 0; a < gyro.size(); ++a) drift[a][i - first] = out.drift[a];
  }
  return drift;
}

std::string model_kind_label(const ModelStudy& m, std::size_t axis);

// "SVR + AFSA", with the feature terms when they are not the paper's pair.
std::string model_label(const ModelStudy& m, std::size_t axis) {
  const std::string kind = model_kind_label(m, axis);
  if (m.features == "dT,rate") return kind;
  return kind + (m.features == "auto" ? ", chosen features" : ", " + m.features);
}

std::string model_kind_label(const ModelStudy& m, std::size_t axis) {
  if (m.model == ModelKind::linear) return "linear regression";
  if (m.model == ModelKind::stepwise) return "stepwise regression";
  const auto& tuning = m.calibration.model.axes.at(axis).fit.tuning;
  if (tuning && !tuning->method.empty()) {
    return "SVR + " + (tuning->method == "afsa" ? std::string("AFSA") : tuning->method);
  }
  return "SVR (fixed C, σ)";
}

// The tuning history an SVR fit carries, if it was tuned, labelled with its method.
std::vector<TuningHistory> tuning_histories(const FitRecord& fit, const std::string& axis) {
  std::vector<TuningHistory> out;
  if (!fit.tuning || fit.tuning->history.empty()) return out;
  TuningHistory h;
  h.label = (fit.tuning->method.empty() ? std::string("AFSA") : fit.tuning->method) + ", " + axis;
  for (const auto& point : fit.tuning->history) {
    h.points.emplace_back(static_cast<double>(point.evaluations), point.best_value);
  }
  out.push_back(std::move(h));
  return out;
}

// Variance of the smoothed noise (gyro - true drift) over rows [begin, end) where the
// trailing window is full, around its mean: what no drift model can remove.
double noise_floor(const ChamberLog& log, std::size_t axis, const std::vector<double>& drift, double window_s,
                   std::size_t begin, std::size_t end) {
  TrailingMean mean(window_s);
  std::vector<double> smoothed;
  for (std::size_t r = 0; r < log.rows(); ++r) {
    const double value = mean.push(log.time[r], log.gyro[axis][r] - drift[r]);
    if (r >= begin && r < end && mean.full()) smoothed.push_back(value);
  }
  if (smoothed.size() < 2) return NAN;
  double m = 0;
  for (double v : smoothed) m += v;
  m /= static_cast<double>(smoothed.size());
  double variance = 0;
  for (double v : smoothed) variance += (v - m) * (v - m);
  return variance / static_cast<double>(smoothed.size());
}

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

nlohmann::json metrics_cell(const ResidualMetrics& metrics, double floor) {
  return {{"mse", metrics.mse_after},
          {"ratio_to_floor", number_or_null(std::isfinite(floor) && floor > 0 ? metrics.mse_after / floor : NAN)},
          {"residual_std", metrics.residual_std},
          {"residual_peak_to_peak", metrics.residual_peak_to_peak}};
}

}  // namespace

ReportOptions paper_report_options(std::uint64_t seed, int threads, long evaluations,
                                   FeatureSelectionOptions::Method identify,
                                   std::vector<std::string> other_terms, StopToken stop) {
  ReportOptions options;
  options.seed = seed;
  options.threads = std::max(1, threads);
  CalibrationOptions& calibration = options.study.calibration;
  calibration.stop = stop;
  calibration.svr.threads = options.threads;
  SvrTuningOptions tuning;
  tuning.threads = options.threads;
  tuning.seed = seed;
  tuning.evaluations = evaluations;
  calibration.tuning = tuning;
  calibration.selection.threads = options.threads;  // axes searched at once
  calibration.selection.method = identify;
  options.study.other_terms = std::move(other_terms);
  return options;
}

ReportResult write_report(const ChamberLog& log, const LogSpec& spec, const ReportOptions& options) {
  namespace fs = std::filesystem;
  // The folder appears whole or not at all (io/atomic_file.hpp): everything is written
  // into a staging folder beside it and committed at the end, so an error or a stop
  // leaves out_dir as it was. A folder that exists keeps the files the report does not write.
  const fs::path target(options.out_dir);
  std::error_code parents_made;  // if not, StagedFolder says why
  if (!options.out_dir.empty() && target.has_parent_path()) fs::create_directories(target.parent_path(), parents_made);
  StagedFolder staged(options.out_dir);
  const std::string& out_dir = staged.staging();
  const auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  std::vector<std::pair<std::string, double>> timings = options.earlier_steps;
  const StopToken& stop = options.study.calibration.stop;

  ReportResult result;
  StudyOptions study_options = options.study;
  if (!study_options.progress) study_options.progress = options.progress;
  auto start = Clock::now();
  result.study = run_study(log, spec, study_options);
  Study& study = result.study;
  for (const auto& m : study.models) timings.emplace_back("fit " + model_label(m, 0) + " (all axes) and evaluate", m.seconds);

  const std::size_t axes = log.axes();
  const bool known_drift = options.true_drift.size() == axes && axes > 0;
  std::size_t svr_index = study.models.size();
  for (std::size_t m = 0; m < study.models.size(); ++m) {
    if (study.models[m].model == ModelKind::svr && svr_index == study.models.size()) svr_index = m;  // the paper's pair
  }

  // Cross-axis experiment with the SVR's options.
  std::vector<CrossAxisResult> cross;
  const ChamberLog training = slice_rows(log, 0, study.split_row);
  const ChamberLog held_out = slice_rows(log, study.split_row, log.rows());
  if (axes >= 2 && svr_index < study.models.size()) {
    say(fmt::format("cross-axis experiment: {} SVR fits, each on the pooled other axes", axes));
    start = Clock::now();
    CalibrationOptions cross_options = options.study.calibration;
    cross = run_cross_axis(training, held_out, log, study.models[svr_index].calibration.model, cross_options);
    timings.emplace_back("cross-axis experiment", seconds_since(start));
  }

  // Compensation of every axis by every model over the whole log; Allan deviation on the
  // held-out part.
  say("compensating every axis with every model; Allan deviation before and after");
  start = Clock::now();
  // What each model's compensator subtracts from the held-out rows (the drift at the row's
  // time, compensate/compensator.hpp): the Allan deviation is of the rate it leaves.
  std::vector<std::vector<std::vector<double>>> subtracted(study.models.size());
  for (std::size_t m = 0; m < study.models.size(); ++m) {
    stop.throw_if_requested("compensation and Allan deviation");
    subtracted[m] = compensator_drift(study.models[m].calibration.model, log, study.split_row);
  }
  FigureInputs figures;
  figures.log = &log;
  figures.split_time = study.split_time;
  figures.svr_index = svr_index < study.models.size() ? svr_index : 0;
  const double sample_rate = 1.0 / median_step(log);
  for (const auto& m : study.models) figures.model_labels.push_back(model_label(m, 0));
  for (std::size_t a = 0; a < axes; ++a) {
    stop.throw_if_requested("compensation and Allan deviation");
    const auto& pipeline = study.models.front().calibration.model.axes[a].pipeline;
    const FeatureTable table = feature_table({log}, pipeline, a, false);
    AxisTrace trace;
    trace.name = log.gyro_names[a];
    trace.time_s = table.time;
    trace.smoothed.assign(table.target.data(), table.target.data() + table.target.size());
    if (known_drift) {
      for (auto row : table.row) trace.true_drift.push_back(options.true_drift[a][row]);
    }
    for (const auto& m : study.models) {
      // On the model's own terms: the chosen features are not the paper's pair (the table
      // above), and a model predicting from another's columns read past them.
      const AxisModel& model = m.calibration.model.axes[a];
      const bool same_terms = model.pipeline.terms == pipeline.terms;
      const FeatureTable own = same_terms ? FeatureTable{} : feature_table({log}, model.pipeline, a, false);
      const FeatureTable& rows = same_terms ? table : own;
      if (rows.row != table.row) throw Error(fmt::format("report: {} is ready on other rows than the paper's pair", m.features));
      const Eigen::VectorXd p = model.predict(rows.features);
      trace.prediction.emplace_back(p.data(), p.data() + p.size());
    }
    for (const auto& c : cross) {
      if (c.left_out != a) continue;
      const Eigen::VectorXd p = c.model.predict(table.features);
      trace.cross_prediction.assign(p.data(), p.data() + p.size());
    }
    AxisAllan allan;
    allan.name = trace.name;
    const auto first = static_cast<std::size_t>(
        std::lower_bound(table.row.begin(), table.row.end(), study.split_row) - table.row.begin());
    std::vector<double> raw;
    for (std::size_t i = first; i < table.rows(); ++i) raw.push_back(log.gyro[a][table.row[i]]);
    allan.curves.push_back({"raw output", overlapping_allan_deviation(raw, sample_rate)});
    for (std::size_t m = 0; m < study.models.size(); ++m) {
      std::vector<double> compensated(raw.size());
      for (std::size_t i = first; i < table.rows(); ++i) {
        compensated[i - first] = raw[i - first] - subtracted[m][a][table.row[i] - study.split_row];
      }
      allan.curves.push_back({"minus " + figures.model_labels[m], overlapping_allan_deviation(compensated, sample_rate)});
    }
    figures.allan.push_back(std::move(allan));
    figures.axes.push_back(std::move(trace));
    if (svr_index < study.models.size()) {
      for (auto& h : tuning_histories(study.models[svr_index].calibration.model.axes[a].fit, log.gyro_names[a])) {
        figures.tuning.push_back(std::move(h));
      }
    }
  }
  stop.throw_if_requested("report");
  for (const auto& m : study.models) {
    save_drift_model(m.calibration.model, (fs::path(out_dir) / ("model_" + std::string(to_string(m.model)) + ".json")).string());
  }
  timings.emplace_back("compensation, Allan deviation, model files", seconds_since(start));

  say("drawing the figures with gnuplot");
  start = Clock::now();
  FigureOutcome drawn = draw_figures(figures, out_dir, options.gnuplot, stop);
  result.figures_drawn = drawn.drawn;
  result.figures_note = drawn.note;
  timings.emplace_back("figures (gnuplot)", seconds_since(start));

  // The summary: every number the page shows.
  stop.throw_if_requested("report");
  start = Clock::now();
  nlohmann::json summary;
  summary["title"] = options.title;
  summary["command"] = options.command_line;
  summary["data"] = {{"source", log.source},
                     {"rows", log.rows()},
                     {"axes", log.gyro_names},
                     {"temperatures", log.temperature_names},
                     {"duration_s", log.rows() ? log.time.back() - log.time.front() : 0.0},
                     {"sample_rate_hz", sample_rate},
                     {"true_drift_known", known_drift}};
  summary["split"] = {{"row", study.split_row},
                      {"time_s", study.split_time},
                      {"description", study.split_description},
                      {"training_rows", study.split_row},
                      {"held_out_rows", log.rows() - study.split_row}};
  const auto& calibration = options.study.calibration;
  const auto& pipeline = study.models.front().calibration.model.axes.front().pipeline;
  nlohmann::json svr_params = nlohmann::json::array();
  if (svr_index < study.models.size()) {
    for (const auto& axis : study.models[svr_index].calibration.model.axes) {
      nlohmann::json entry = {{"axis", axis.name}};
      if (axis.fit.params) entry["params"] = to_json(*axis.fit.params);
      if (axis.fit.evaluations) entry["evaluations"] = *axis.fit.evaluations;
      if (axis.fit.tuning) entry["tuning"] = to_json(*axis.fit.tuning);
      if (axis.fit.solver) entry["solver"] = to_json(*axis.fit.solver);
      svr_params.push_back(entry);
    }
  }
  summary["parameters"] = {{"smooth_seconds", pipeline.smooth_seconds},
                           {"rate_span_seconds", pipeline.rate_span_seconds},
                           {"decimation", pipeline.decimation},
                           {"terms", pipeline.term_names()},
                           {"svr_options", {{"C", calibration.svr.C},
                                            {"gamma", calibration.svr.gamma},
                                            {"sigma", 1.0 / std::sqrt(2.0 * calibration.svr.gamma)},
                                            {"epsilon", calibration.svr.epsilon},
                                            {"tolerance", calibration.svr.tolerance}}},
                           {"svr_per_axis", svr_params},
                           {"seed", options.seed},
                           {"threads", options.threads}};

  std::vector<double> floor_in(axes, NAN), floor_out(axes, NAN);
  if (known_drift) {
    for (std::size_t a = 0; a < axes; ++a) {
      floor_in[a] = noise_floor(log, a, options.true_drift[a], pipeline.smooth_seconds, 0, study.split_row);
      floor_out[a] = noise_floor(log, a, options.true_drift[a], pipeline.smooth_seconds, study.split_row, log.rows());
    }
  }
  // The noise floor as fit estimates it from the training part alone, for fit's figure
  // (expected held-out MSE over it) and its far-from-floor warning.
  std::vector<double> floor_estimate(axes, NAN);
  if (pipeline.smooth_seconds > 0) {
    for (std::size_t a = 0; a < axes; ++a) {
      const auto estimate = estimate_noise_floor(std::span(log.time).first(study.split_row),
                                                 std::span(log.gyro[a]).first(study.split_row), pipeline.smooth_seconds);
      if (estimate.usable() && estimate.variance > 0) floor_estimate[a] = estimate.variance;
    }
  }
  // Table 1's column order: original drift, SVR, linear, then stepwise.
  std::vector<std::size_t> order;
  for (ModelKind kind : {ModelKind::svr, ModelKind::linear, ModelKind::stepwise}) {
    for (std::size_t m = 0; m < study.models.size(); ++m) {
      if (study.models[m].model == kind) order.push_back(m);
    }
  }
  for (std::size_t m = 0; m < study.models.size(); ++m) {
    if (std::find(order.begin(), order.end(), m) == order.end()) order.push_back(m);
  }
  nlohmann::json columns = nlohmann::json::array();
  for (auto m : order) columns.push_back({{"model", to_string(study.models[m].model)},
                                       {"features", study.models[m].features},
                                       {"label", model_label(study.models[m], 0)}});
  nlohmann::json tables;
  for (const bool is_held_out : {false, true}) {
    nlohmann::json rows = nlohmann::json::array();
    const auto& floors = is_held_out ? floor_out : floor_in;
    for (std::size_t a = 0; a < axes; ++a) {
      const auto& first = is_held_out ? study.models.front().held_out[a] : study.models.front().in_sample[a];
      nlohmann::json row = {{"axis", log.gyro_names[a]},
                            {"samples", first.samples},
                            {"original_mse", first.mse_before},
                            {"noise_floor", number_or_null(floors[a])}};
      nlohmann::json cells = nlohmann::json::array();
      for (auto m : order) {
        const auto& metrics = is_held_out ? study.models[m].held_out[a] : study.models[m].in_sample[a];
        nlohmann::json cell = metrics_cell(metrics, floors[a]);
        cell["model"] = to_string(study.models[m].model);
        cell["features"] = study.models[m].features;
        cell["terms"] = study.models[m].calibration.model.axes[a].pipeline.term_names();
        // Beside the held-out figure, what the training part's blocked CV expected of it.
        const auto expected = expected_held_out(study.models[m].calibration.model.axes[a].fit);
        if (is_held_out && expected) {
          cell["expected_mse"] = expected->cv_mse;
          cell["expected_from"] = expected->from;
          cell["expected_x_floor_estimate"] = number_or_null(expected->cv_mse / floor_estimate[a]);
        }
        cells.push_back(cell);
      }
      row["models"] = cells;
      rows.push_back(row);
    }
    tables[is_held_out ? "held_out" : "in_sample"] = {{"columns", columns}, {"rows", rows}};
  }
  summary["tables"] = tables;

  // fit's far-from-floor warning, one line per model: the expected held-out MSE (the
  // in-sample MSE for a fit without CV) over the training part's floor estimate.
  nlohmann::json warnings = nlohmann::json::array();
  for (auto m : order) {
    const ModelStudy& model = study.models[m];
    std::vector<FloorRatio> held_out, in_sample;
    for (std::size_t a = 0; a < axes; ++a) {
      if (!std::isfinite(floor_estimate[a])) continue;
      if (const auto expected = expected_held_out(model.calibration.model.axes[a].fit)) {
        held_out.push_back({log.gyro_names[a], expected->cv_mse / floor_estimate[a]});
      } else {
        in_sample.push_back({log.gyro_names[a], model.in_sample[a].mse_after / floor_estimate[a]});
      }
    }
    const bool searched = model.features == "auto";
    for (const bool is_held_out : {true, false}) {
      if (const auto line = far_from_floor_warning(is_held_out ? held_out : in_sample, is_held_out, searched, 1,
                                                    "fit --data")) {
        warnings.push_back(fmt::format("{} ({}): {}", to_string(model.model), model.features, *line));
      }
    }
  }
  summary["warnings"] = warnings;

  // How the terms were chosen, axis by axis (--features auto): the models share one
  // least-squares search, whose path the SVR's record extends with the sets it judged.
  nlohmann::json selections = nlohmann::json::array();
  for (std::size_t a = 0; a < axes; ++a) {
    nlohmann::json entry = {{"axis", log.gyro_names[a]}, {"chosen", nlohmann::json::array()}};
    for (const auto& m : study.models) {
      const auto& selection = m.calibration.model.axes[a].fit.feature_selection;
      if (!selection) continue;
      if (!entry.contains("selection") || selection->path.size() > entry["selection"]["path"].size()) {
        entry["selection"] = to_json(*selection);
      }
      entry["chosen"].push_back({{"label", model_kind_label(m, a)},
                                 {"terms", selection->terms},
                                 {"scored_by", selection->scored_by},
                                 {"cv_mse", selection->cv_mse}});
      if (const auto& check = m.calibration.model.axes[a].fit.kernel_check) {
        entry["chosen"].back()["kernel_check"] = to_json(*check);
      }
    }
    if (entry.contains("selection")) selections.push_back(std::move(entry));
  }
  summary["feature_selection"] = selections;

  nlohmann::json cross_json = nlohmann::json::array();
  for (const auto& c : cross) {
    cross_json.push_back({{"left_out", c.left_out_name},
                          {"trained_on", c.training_axes},
                          {"training_samples", c.training_samples},
                          {"held_out_mse", c.held_out.mse_after},
                          {"held_out_original_mse", c.held_out.mse_before},
                          {"own_axis_held_out_mse", study.models[svr_index].held_out[c.left_out].mse_after},
                          {"whole_log_mse", c.whole_log.mse_after},
                          {"seconds", c.seconds}});
  }
  summary["cross_axis"] = cross_json;

  nlohmann::json allan_json = nlohmann::json::array();
  for (const auto& axis : figures.allan) {
    nlohmann::json curves = nlohmann::json::array();
    for (const auto& curve : axis.curves) {
      nlohmann::json points = nlohmann::json::array();
      for (const auto& p : curve.points) points.push_back({p.tau_s, p.deviation});
      curves.push_back({{"label", curve.label}, {"tau_s_adev_dph", points}});
    }
    allan_json.push_back({{"axis", axis.name}, {"curves", curves}});
  }
  summary["allan_deviation_held_out"] = allan_json;
  nlohmann::json figures_json = nlohmann::json::array();
  for (const auto& f : drawn.figures) figures_json.push_back({{"file", f.file}, {"title", f.title}});
  summary["figures"] = drawn.drawn ? figures_json : nlohmann::json::array();
  summary["figures_note"] = drawn.note;
  summary["study"] = study.to_json();

  const std::string html_path = (fs::path(out_dir) / "report.html").string();
  const std::string summary_path = (fs::path(out_dir) / "summary.json").string();
  timings.emplace_back("summary and page", seconds_since(start));
  nlohmann::json timing_json = nlohmann::json::array();
  double total = 0;
  for (const auto& [step, seconds] : timings) {
    timing_json.push_back({{"step", step}, {"seconds", seconds}});
    total += seconds;
  }
  summary["timings"] = timing_json;
  summary["total_seconds"] = total;
  write_file_atomically(summary_path, summary.dump(1) + "\n");
  write_file_atomically(html_path, render_html(summary, drawn, out_dir));
  stop.throw_if_requested("report");
  staged.commit();
  result.html_path = staged.committed_path(html_path);
  result.summary_path = staged.committed_path(summary_path);
  result.summary = std::move(summary);
  return result;
}

}  // namespace thermodrift
