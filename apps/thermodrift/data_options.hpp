// The data options every command that reads a log shares (CLI.md, "Data options").
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/tune/feature_selection.hpp"

namespace thermodrift::cli {

struct DataOptions {
  std::vector<std::string> files;
  std::string format = "csv";
  std::string time;
  double rate = 0;
  std::vector<std::string> gyro;
  std::vector<std::string> temperature;
  std::string gyro_unit;  // empty: not given (dph, or the model's)
  std::string time_unit;  // empty: not given (s, or the model's)
  std::vector<double> temperature_scale;  // empty: not given (1, or the model's)
  std::vector<double> temperature_offset;
  std::vector<double> gyro_scale;
  double smooth = 100;
  bool despike = false;  // --despike: the causal Hampel filter (io/despike.hpp)
  const CLI::Option* smooth_option = nullptr;  // set by add_to

  // Declares --data, --format, --time, --rate, --gyro, --temp, --gyro-unit, --time-unit,
  // --temp-scale, --temp-offset, --gyro-scale, --smooth; --data required unless told.
  void add_to(CLI::App& app, bool data_required = true);

  // The LogSpec the options name. UsageError for a zero or non-finite scale.
  LogSpec spec() const;
  // The model's LogSpec (its columns, units and scaling, as fit read the training log),
  // with any of those options given on the command line taking over: the log at hand
  // may be named or recorded differently; the model itself works in °C, °/h and s.
  // UsageError for a --smooth other than the model's (check_smoothing).
  LogSpec spec_for(const DriftModel& model) const;
  // A --smooth that differs from the model's window is a UsageError (spec_for checks it:
  // evaluate and compensate smooth as the model was fitted, never silently otherwise).
  void check_smoothing(const DriftModel& model) const;
  // The warm-up of a pipeline with --smooth and `rate_span` (0: the default, the smoothing
  // window, at least 1 s), as calibrate builds it.
  double warm_up_seconds(double rate_span = 0) const {
    return smooth + (rate_span > 0 ? rate_span : std::max(smooth, 1.0));
  }

  // Reads every --data file; warnings (skipped banners, dropped rows) go to stderr. A
  // burst log whose bursts are shorter than `warm_up_seconds` (the pipeline's smoothing +
  // rate span) is collapsed to one sample per burst (io/bursts.hpp), said in one line.
  // `stop` is asked while reading (Interrupted).
  std::vector<ChamberLog> read(const LogSpec& spec, double warm_up_seconds, const StopToken& stop) const;
};

// Declares --identify thermal-node|greedy (how `--features auto` finds the terms) for fit,
// report and demo.
void add_identify_option(CLI::App& app, FeatureSelectionOptions::Method& method);
// --identify given without auto among `features` is a UsageError: it would be ignored.
void check_identify(const CLI::App& app, const std::vector<std::string>& features);

// "thermodrift: warning: ..." on stderr, or to the sink set_warning_sink installed.
void warn(const std::string& message);
// Where warn() sends its messages from now on (the Python package: Python's warnings);
// an empty function restores stderr.
void set_warning_sink(std::function<void(const std::string&)> sink);

// "thermodrift: FILE: despike replaced N samples (gyro_x 1, temp_x 0, ...)" on stderr.
void note_despiked(const std::string& file, const std::vector<std::string>& gyro_names,
                   const std::vector<std::size_t>& gyro, const std::vector<std::string>& temperature_names,
                   const std::vector<std::size_t>& temperature);

}  // namespace thermodrift::cli
