#include "thermodrift/report/study.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "thermodrift/error.hpp"
#include "thermodrift/io/time_stamp.hpp"

namespace thermodrift {

nlohmann::json Study::to_json() const {
  nlohmann::json models_json = nlohmann::json::array();
  for (const auto& m : models) {
    nlohmann::json axes = nlohmann::json::array();
    for (std::size_t a = 0; a < m.in_sample.size(); ++a) {
      const auto& axis = m.calibration.model.axes[a];
      axes.push_back({{"name", axis.name},
                      {"in_sample", m.in_sample[a].to_json()},
                      {"held_out", m.held_out[a].to_json()},
                      {"fit", fit_record_to_json(axis.fit)}});
    }
    models_json.push_back({{"model", to_string(m.model)}, {"features", m.features}, {"seconds", m.seconds}, {"axes", axes}});
  }
  return {{"split", {{"row", split_row}, {"time_s", split_time}, {"description", split_description}}},
          {"models", models_json}};
}

Study run_study(const ChamberLog& log, const LogSpec& spec, const StudyOptions& options) {
  Study study;
  if (options.split_row) {
    study.split_row = *options.split_row;
    study.split_description = fmt::format("held out from row {} on", study.split_row);
  } else {
    study.split_row = static_cast<std::size_t>(std::floor(static_cast<double>(log.rows()) *
                                                          (1.0 - options.holdout_fraction)));
    study.split_description = fmt::format("last {:.0f} % of the log held out", 100 * options.holdout_fraction);
  }
  if (study.split_row == 0 || study.split_row >= log.rows()) {
    throw UsageError(fmt::format("split row {} leaves no training or no held-out data", study.split_row));
  }
  study.split_time = log.time[study.split_row];
  if (!options.split_description.empty()) study.split_description = options.split_description;
  const std::vector<ChamberLog> training{slice_rows(log, 0, study.split_row)};
  std::vector<std::vector<std::string>> feature_sets{options.calibration.terms};
  if (!options.other_terms.empty() && options.other_terms != options.calibration.terms) {
    feature_sets.push_back(options.other_terms);
  }
  for (const auto& terms : feature_sets) {
    CalibrationOptions shared = options.calibration;
    shared.terms = terms;
    if (chooses_features(shared) && options.models.size() > 1) {
      // One least-squares search per axis serves every model (an SVR then judges its sets).
      if (options.progress) options.progress("choosing feature terms per axis (least squares, blocked CV)");
      shared.selections = select_features_per_axis(training, shared);
    }
    for (const auto& name : options.models) {
      const std::string features = fmt::format("{}", fmt::join(terms, ","));
      if (options.progress) {
        options.progress(fmt::format("fitting {} ({}) on {} rows", name, features, training.front().rows()));
      }
      const auto start = std::chrono::steady_clock::now();
      ModelStudy entry;
      entry.model = name;
      entry.features = features;
      CalibrationOptions calibration_options = shared;
      calibration_options.model = name;
      entry.calibration = calibrate(training, spec, calibration_options);
      for (const auto& axis : entry.calibration.axes) entry.in_sample.push_back(axis.in_sample);
      entry.held_out = evaluate_from(entry.calibration.model, log, study.split_row);
      entry.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      study.models.push_back(std::move(entry));
    }
  }
  return study;
}

std::size_t row_at_time(const ChamberLog& log, std::string_view when) {
  TimeStamp at;
  std::string problem;
  if (!parse_time_stamp(when, TimeUnit::s, at, &problem)) throw UsageError("--split-time: " + problem);
  double since_first_row = at.approximate_seconds();
  if (log.time_origin) {
    since_first_row = at.seconds_since(log.time_origin->stamp);  // exact: epochs keep their last digit
  } else if (looks_like_iso_8601(when)) {
    throw UsageError(fmt::format("--split-time {}: the log has no time column, so give seconds from its first row",
                                 when));
  }
  return static_cast<std::size_t>(std::lower_bound(log.time.begin(), log.time.end(), since_first_row) -
                                  log.time.begin());
}

}  // namespace thermodrift
