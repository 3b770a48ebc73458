#include "data_options.hpp"
#include "lists.hpp"
#include "numbers.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstdio>

#include "thermodrift/error.hpp"
#include "thermodrift/io/bursts.hpp"

namespace thermodrift::cli {

namespace {
std::function<void(const std::string&)>& warning_sink() {
  static std::function<void(const std::string&)> sink;
  return sink;
}
}  // namespace

void set_warning_sink(std::function<void(const std::string&)> sink) { warning_sink() = std::move(sink); }

void warn(const std::string& message) {
  if (const auto& sink = warning_sink()) return sink(message);
  std::fprintf(stderr, "thermodrift: warning: %s\n", message.c_str());
}

void note_despiked(const std::string& file, const std::vector<std::string>& gyro_names,
                   const std::vector<std::size_t>& gyro, const std::vector<std::string>& temperature_names,
                   const std::vector<std::size_t>& temperature) {
  std::size_t total = 0;
  std::vector<std::string> parts;
  for (std::size_t a = 0; a < gyro.size() && a < gyro_names.size(); ++a) {
    total += gyro[a];
    parts.push_back(fmt::format("{} {}", gyro_names[a], gyro[a]));
  }
  for (std::size_t c = 0; c < temperature.size() && c < temperature_names.size(); ++c) {
    total += temperature[c];
    parts.push_back(fmt::format("{} {}", temperature_names[c], temperature[c]));
  }
  std::fprintf(stderr, "thermodrift: %s: despike replaced %zu sample%s (%s)\n", file.c_str(), total,
               total == 1 ? "" : "s", fmt::format("{}", fmt::join(parts, ", ")).c_str());
}

void DataOptions::add_to(CLI::App& app, bool data_required) {
  app.add_option("--data", files, "the log(s): CSV, header row or not; several are fitted together")
      ->required(data_required)
      ->check(CLI::ExistingFile);
  app.add_option("--format", format, "csv (default) or libsvm")
      ->check(CLI::IsMember({"csv", "libsvm"}));
  app.add_option("--time", time, "time column (in --time-unit, or ISO 8601 stamps), header name or 1-based index");
  app.add_option("--rate", rate,
                 "sampling rate in Hz, for a log without a time column (a time column is then not read; not with "
                 "--time)")
      ->check(kSampleRate);
  add_list_option(app, "--gyro", gyro, "gyro column(s), one model per axis");
  add_list_option(app, "--temp", temperature,
                  "temperature column(s): one for all axes or one per axis, then any extra channels grad:A-B terms read");
  app.add_option("--gyro-unit", gyro_unit, "unit of the gyro columns: dph (°/h, default), dps (°/s), radps")
      ->check(CLI::IsMember({"dph", "dps", "radps"}));
  app.add_option("--time-unit", time_unit,
                 "unit of the numbers in the time column: s (default), ms, us, ns; ISO 8601 stamps are recognised "
                 "without it")
      ->check(CLI::IsMember({"s", "ms", "us", "ns"}));
  add_number_list_option(app, "--temp-scale", temperature_scale,
                         "raw temperature to °C: °C = A·raw + B; one A for all temperature columns or one per column "
                         "(default 1)");
  add_number_list_option(app, "--temp-offset", temperature_offset,
                         "B of --temp-scale; one for all temperature columns or one per column (default 0)");
  add_number_list_option(app, "--gyro-scale", gyro_scale,
                         "multiplies the gyro columns after --gyro-unit; one for all or one per gyro column (default 1)");
  smooth_option = app.add_option("--smooth", smooth, "moving-average window in seconds (default 100)")
                      ->check(kNonNegative);
  app.add_flag("--despike", despike,
               "replace isolated outliers of every gyro and temperature column (a causal Hampel filter: more than "
               "6 robust sigmas from the median of the 30 samples before); off by default; the model keeps it");
}

LogSpec DataOptions::spec() const {
  if (!time.empty() && rate > 0) {
    throw UsageError("--time and --rate: give one (the time column, or the sampling rate of a log without one)");
  }
  LogSpec spec;
  if (!time.empty()) spec.time_column = time;
  if (rate > 0) spec.rate_hz = rate;
  spec.gyro_columns = gyro;
  spec.temperature_columns = temperature;
  spec.gyro_unit = parse_gyro_unit(gyro_unit.empty() ? "dph" : gyro_unit);
  if (!time_unit.empty()) spec.time_unit = parse_time_unit(time_unit);
  spec.scaling = {temperature_scale, temperature_offset, gyro_scale};
  spec.scaling.check(0, 0);  // values now; their counts against the columns when the log is opened
  if (despike) spec.despike = DespikeOptions{};
  return spec;
}

void DataOptions::check_smoothing(const DriftModel& model) const {
  if (smooth_option == nullptr || smooth_option->count() == 0) return;
  for (const auto& axis : model.axes) {
    if (axis.pipeline.smooth_seconds != smooth) {
      throw UsageError(fmt::format("--smooth {:g}: the model was fitted with a {:g} s window and is applied with "
                                   "it; fit again to change it",
                                   smooth, axis.pipeline.smooth_seconds));
    }
  }
}

LogSpec DataOptions::spec_for(const DriftModel& model) const {
  check_smoothing(model);
  LogSpec spec = model.log_spec();
  if (!time.empty()) {
    spec.time_column = time;
    spec.rate_hz.reset();
  }
  if (rate > 0) {
    spec.rate_hz = rate;
    spec.time_column.reset();
  }
  if (!gyro.empty()) spec.gyro_columns = gyro;
  if (!temperature.empty()) spec.temperature_columns = temperature;
  const LogSpec given = this->spec();
  if (!gyro_unit.empty()) spec.gyro_unit = given.gyro_unit;
  if (!time_unit.empty()) spec.time_unit = given.time_unit;
  if (!temperature_scale.empty()) spec.scaling.temperature_scale = temperature_scale;
  if (!temperature_offset.empty()) spec.scaling.temperature_offset = temperature_offset;
  if (!gyro_scale.empty()) spec.scaling.gyro_scale = gyro_scale;
  if (despike && !spec.despike) spec.despike = DespikeOptions{};
  if (spec.gyro_columns.size() != model.axes.size()) {
    throw UsageError(fmt::format("the model has {} axes but {} gyro columns were named",
                                 model.axes.size(), spec.gyro_columns.size()));
  }
  return spec;
}

std::vector<ChamberLog> DataOptions::read(const LogSpec& spec, double warm_up_seconds, const StopToken& stop) const {
  if (format != "csv") throw UsageError("this command reads CSV logs only (--format csv)");
  std::vector<ChamberLog> logs;
  for (const auto& file : files) {
    logs.push_back(read_chamber_log(file, spec, stop));
    for (const auto& warning : logs.back().warnings) warn(warning);
    if (spec.despike) {
      const ChamberLog& log = logs.back();
      note_despiked(file, log.gyro_names, log.despiked_gyro, log.temperature_names, log.despiked_temperature);
    }
    if (const auto bursts = find_bursts(logs.back(), warm_up_seconds)) {
      logs.back() = collapse_bursts(logs.back(), *bursts);
      std::fprintf(stderr, "thermodrift: %s: burst log, %s: each burst's mean is one sample (%zu rows -> %zu); "
                   "smoothing and rates work on the burst means\n",
                   file.c_str(), bursts->describe().c_str(), bursts->rows, logs.back().rows());
    }
  }
  return logs;
}

void check_identify(const CLI::App& app, const std::vector<std::string>& features) {
  if (app.count("--identify") && std::find(features.begin(), features.end(), "auto") == features.end()) {
    throw UsageError("--identify applies to --features auto (how it chooses the terms)");
  }
}

void add_identify_option(CLI::App& app, FeatureSelectionOptions::Method& method) {
  app.add_option_function<std::string>(
         "--identify",
         [&method](const std::string& name) {
           method = name == "greedy" ? FeatureSelectionOptions::Method::greedy
                                     : FeatureSelectionOptions::Method::thermal_node;
         },
         "with --features auto: thermal-node (default; one node's lags, a piecewise-linear map of its "
         "temperature and linear dynamic terms) or greedy (a forward search over single terms); "
         "docs/features.md")
      ->check(CLI::IsMember({"thermal-node", "greedy"}))
      ->option_text("thermal-node|greedy");
}

}  // namespace thermodrift::cli
