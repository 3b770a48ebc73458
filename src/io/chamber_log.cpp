#include "thermodrift/io/chamber_log.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <numbers>

#include "thermodrift/error.hpp"

namespace thermodrift {

GyroUnit parse_gyro_unit(std::string_view name) {
  if (name == "dph") return GyroUnit::dph;
  if (name == "dps") return GyroUnit::dps;
  if (name == "radps") return GyroUnit::radps;
  throw UsageError(fmt::format("unknown gyro unit '{}' (expected dph, dps or radps)", name));
}

std::string_view to_string(GyroUnit unit) {
  switch (unit) {
    case GyroUnit::dph: return "dph";
    case GyroUnit::dps: return "dps";
    case GyroUnit::radps: return "radps";
  }
  return "dph";
}

double degrees_per_hour(GyroUnit unit) {
  switch (unit) {
    case GyroUnit::dph: return 1.0;
    case GyroUnit::dps: return 3600.0;
    case GyroUnit::radps: return 3600.0 * 180.0 / std::numbers::pi;
  }
  return 1.0;
}

namespace {

double value_of(const std::vector<double>& values, std::size_t column, double fallback) {
  if (values.empty()) return fallback;
  return values.size() == 1 ? values.front() : values.at(column);
}

void check_values(const std::vector<double>& values, std::size_t columns, const char* option, const char* kind,
                  bool is_scale) {
  if (columns > 0 && values.size() > 1 && values.size() != columns) {
    throw UsageError(fmt::format("{} has {} values for {} {} column{}: give one for all or one per column", option,
                                 values.size(), columns, kind, columns == 1 ? "" : "s"));
  }
  for (const double value : values) {
    if (!std::isfinite(value) || (is_scale && value == 0)) {
      throw UsageError(fmt::format("{} must be a finite{} number, not {}", option, is_scale ? ", non-zero" : "", value));
    }
  }
}

}  // namespace

bool LogScaling::is_default() const {
  auto all = [](const std::vector<double>& values, double value) {
    return std::all_of(values.begin(), values.end(), [&](double v) { return v == value; });
  };
  return all(temperature_scale, 1) && all(temperature_offset, 0) && all(gyro_scale, 1);
}

double LogScaling::temperature_scale_of(std::size_t column) const { return value_of(temperature_scale, column, 1); }
double LogScaling::temperature_offset_of(std::size_t column) const { return value_of(temperature_offset, column, 0); }
double LogScaling::gyro_scale_of(std::size_t column) const { return value_of(gyro_scale, column, 1); }

void LogScaling::check(std::size_t gyro_columns, std::size_t temperature_columns) const {
  check_values(temperature_scale, temperature_columns, "--temp-scale", "temperature", true);
  check_values(temperature_offset, temperature_columns, "--temp-offset", "temperature", false);
  check_values(gyro_scale, gyro_columns, "--gyro-scale", "gyro", true);
}

namespace {

std::optional<std::size_t> as_index(std::string_view name) {
  std::size_t index = 0;
  const auto* end = name.data() + name.size();
  const auto result = std::from_chars(name.data(), end, index);
  if (name.empty() || result.ec != std::errc{} || result.ptr != end) return std::nullopt;
  return index;
}

std::string column_label(const CsvReader& reader, std::size_t index) {
  return reader.has_header() ? reader.header()[index] : fmt::format("column {}", index + 1);
}

// A column found by a name the header gives twice would be a guess between the two, and
// two gyro axes found as gyro_x were fitted and written as one column read twice.
void refuse_repeated_name(const CsvReader& reader, std::size_t index, const char* role) {
  const auto& header = reader.header();
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (i == index || header[i] != header[index]) continue;
    const auto [first, second] = std::minmax(i, index);
    throw DataError(reader.path(), reader.header_line(), second + 1,
                    fmt::format("the header names '{}' twice (columns {} and {}): the {} column of that name is "
                                "ambiguous; rename one",
                                excerpt(header[index]), first + 1, second + 1, role));
  }
}

// Columns chosen by index may share a header name. The model stores its axes and
// temperature inputs by those names and the compensated columns carry them, so two of
// one name would be one axis written twice, or a log the model could not read again.
void refuse_shared_names(const CsvReader& reader, const std::vector<std::size_t>& chosen, const char* role) {
  if (!reader.has_header()) return;
  for (std::size_t a = 0; a < chosen.size(); ++a) {
    for (std::size_t b = a + 1; b < chosen.size(); ++b) {
      const auto [first, second] = std::minmax(chosen[a], chosen[b]);
      if (first == second || reader.header()[first] != reader.header()[second]) continue;
      throw DataError(reader.path(), reader.header_line(), second + 1,
                      fmt::format("{} columns {} and {} are both named '{}': the model keeps its inputs by "
                                  "name; rename one",
                                  role, first + 1, second + 1, excerpt(reader.header()[first])));
    }
  }
}

std::size_t find_column(const std::string& name, const CsvReader& reader, const char* role) {
  for (std::size_t i = 0; i < reader.header().size(); ++i) {
    if (reader.header()[i] == name) {
      refuse_repeated_name(reader, i, role);
      return i;
    }
  }
  if (const auto index = as_index(name)) {
    if (*index >= 1 && *index <= reader.column_count()) return *index - 1;
    throw DataError(reader.path(), reader.header_line(), 0,
                    fmt::format("{} column {} is out of range: the file has {} columns", role,
                                *index, reader.column_count()));
  }
  if (!reader.has_header()) {
    throw DataError(reader.path(), 0, 0,
                    fmt::format("{} column '{}' named, but the file has no header row; use a "
                                "1-based column index",
                                role, name));
  }
  throw DataError(reader.path(), reader.header_line(), 0,
                  fmt::format("no {} column named '{}' (columns: {})", role, excerpt(name),
                              excerpt(fmt::to_string(fmt::join(reader.header(), ", ")), 200)));
}

std::string lower_case(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Header names starting with `prefix` (lower case), whatever their case: Gyro_X, TEMP1.
std::vector<std::size_t> columns_with_prefix(const CsvReader& reader, std::string_view prefix) {
  std::vector<std::size_t> found;
  for (std::size_t i = 0; i < reader.header().size(); ++i) {
    if (lower_case(reader.header()[i]).starts_with(prefix)) found.push_back(i);
  }
  return found;
}

// The time column found by name: time_s, time or t first, else the first name (any case)
// that is t or starts with "time" or "t_" (time_ms, timestamp, Time (s), t_us).
std::optional<std::size_t> time_column_by_name(const CsvReader& reader) {
  const auto& header = reader.header();
  for (const char* name : {"time_s", "time", "t"}) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return i;
    }
  }
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string name = lower_case(header[i]);
    if (name == "t" || name.starts_with("time") || name.starts_with("t_")) return i;
  }
  return std::nullopt;
}

}  // namespace

LogColumns resolve_columns(const LogSpec& spec, const CsvReader& reader) {
  LogColumns columns;
  if (spec.time_column) {
    columns.time = find_column(*spec.time_column, reader, "time");
  } else if (!spec.rate_hz) {
    columns.time = time_column_by_name(reader);
    if (!columns.time) {
      throw UsageError(fmt::format("{}: no time column found; name one with --time or give the "
                                   "sampling rate with --rate",
                                   reader.path()));
    }
    refuse_repeated_name(reader, *columns.time, "time");
  } else if (!(*spec.rate_hz > 0) || !std::isfinite(*spec.rate_hz)) {
    throw UsageError(fmt::format("--rate must be a positive number of hertz, not {}", *spec.rate_hz));
  }

  if (spec.gyro_columns.empty()) {
    columns.gyro = columns_with_prefix(reader, "gyro");
    if (columns.gyro.empty()) {
      throw UsageError(fmt::format("{}: no column named gyro*; name the gyro columns with --gyro",
                                   reader.path()));
    }
    for (const std::size_t index : columns.gyro) refuse_repeated_name(reader, index, "gyro");
  } else {
    for (const auto& name : spec.gyro_columns) {
      const std::size_t index = find_column(name, reader, "gyro");
      // Two axes on one column would be one axis fitted and written twice.
      if (const auto same = std::find(columns.gyro.begin(), columns.gyro.end(), index); same != columns.gyro.end()) {
        throw UsageError(fmt::format("--gyro names column {} twice ('{}' and '{}'): one column per axis",
                                     excerpt(column_label(reader, index)),
                                     excerpt(spec.gyro_columns[static_cast<std::size_t>(same - columns.gyro.begin())]),
                                     excerpt(name)));
      }
      columns.gyro.push_back(index);
    }
  }
  if (spec.temperature_columns.empty()) {
    columns.temperature = columns_with_prefix(reader, "temp");
    if (columns.temperature.empty()) {
      throw UsageError(fmt::format(
          "{}: no column named temp*; name the temperature columns with --temp", reader.path()));
    }
    for (const std::size_t index : columns.temperature) refuse_repeated_name(reader, index, "temperature");
    // Found by name, channels beyond one per axis would be paired with the axes by their
    // order in the file (a chamber column first would feed the first axis): ask instead.
    if (columns.temperature.size() != 1 && columns.temperature.size() != columns.gyro.size()) {
      std::vector<std::string> names;
      for (auto index : columns.temperature) names.push_back(column_label(reader, index));
      throw UsageError(fmt::format("{}: {} temp* columns ({}) for {} gyro axes; name one for all axes or one "
                                   "per axis with --temp (further columns serve grad terms)",
                                   reader.path(), names.size(), excerpt(fmt::to_string(fmt::join(names, ",")), 200),
                                   columns.gyro.size()));
    }
  } else {
    for (const auto& name : spec.temperature_columns) {
      columns.temperature.push_back(find_column(name, reader, "temperature"));
    }
  }
  spec.scaling.check(columns.gyro.size(), columns.temperature.size());
  refuse_shared_names(reader, columns.gyro, "gyro");
  refuse_shared_names(reader, columns.temperature, "temperature");
  for (auto index : columns.gyro) columns.gyro_names.push_back(column_label(reader, index));
  for (auto index : columns.temperature) {
    columns.temperature_names.push_back(column_label(reader, index));
  }
  return columns;
}

double median_step(const ChamberLog& log) {
  std::vector<double> steps;
  for (std::size_t r = 1; r < log.rows(); ++r) steps.push_back(log.time[r] - log.time[r - 1]);
  if (steps.empty()) return 1.0;
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

ChamberLog without_rows(const ChamberLog& log) {
  ChamberLog out;
  out.source = log.source;
  out.time_origin = log.time_origin;
  out.gyro_names = log.gyro_names;
  out.temperature_names = log.temperature_names;
  return out;
}

ChamberLog slice_rows(const ChamberLog& log, std::size_t begin, std::size_t end) {
  end = std::min(end, log.rows());
  begin = std::min(begin, end);
  auto cut = [&](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(begin),
                               v.begin() + static_cast<std::ptrdiff_t>(end));
  };
  ChamberLog part = without_rows(log);
  part.time = cut(log.time);
  part.bursts = log.bursts;  // its rows are still burst means
  for (const auto& g : log.gyro) part.gyro.push_back(cut(g));
  for (const auto& t : log.temperature) part.temperature.push_back(cut(t));
  part.line.assign(log.line.begin() + static_cast<std::ptrdiff_t>(begin),
                   log.line.begin() + static_cast<std::ptrdiff_t>(end));
  return part;
}

ChamberLog with_ramp_history(const ChamberLog& log, double span_seconds, double fit_seconds) {
  if (log.rows() < 2 || !(span_seconds > 0)) return log;
  const double step = std::max(median_step(log), 1.0);
  const auto count = static_cast<std::size_t>(span_seconds / step);
  const double start = log.time.front();
  // The rows the line is fitted to: the first fit_seconds, two at least.
  std::size_t fitted = 2;
  while (fitted < log.rows() && log.time[fitted] - start <= fit_seconds) ++fitted;

  ChamberLog out = without_rows(log);
  out.bursts = log.bursts;
  out.warnings = log.warnings;
  for (std::size_t k = count; k > 0; --k) out.time.push_back(start - step * static_cast<double>(k));
  out.time.insert(out.time.end(), log.time.begin(), log.time.end());
  out.line.assign(count, 0);
  out.line.insert(out.line.end(), log.line.begin(), log.line.end());
  for (const auto& gyro : log.gyro) {
    std::vector<double> column(count, gyro.front());
    column.insert(column.end(), gyro.begin(), gyro.end());
    out.gyro.push_back(std::move(column));
  }
  for (const auto& temperature : log.temperature) {
    // Least squares on t - start: the slope and the line's value at the start.
    double mean_t = 0, mean_v = 0;
    for (std::size_t i = 0; i < fitted; ++i) mean_t += log.time[i] - start, mean_v += temperature[i];
    mean_t /= static_cast<double>(fitted), mean_v /= static_cast<double>(fitted);
    double covariance = 0, variance = 0;
    for (std::size_t i = 0; i < fitted; ++i) {
      const double dt = log.time[i] - start - mean_t;
      covariance += dt * (temperature[i] - mean_v), variance += dt * dt;
    }
    const double slope = variance > 0 ? covariance / variance : 0;
    const double at_start = mean_v - slope * mean_t;
    const auto [low, high] = std::minmax_element(temperature.begin(), temperature.end());
    std::vector<double> column;
    column.reserve(count + log.rows());
    for (std::size_t k = 0; k < count; ++k) {
      column.push_back(std::clamp(at_start + slope * (out.time[k] - start), *low, *high));
    }
    column.insert(column.end(), temperature.begin(), temperature.end());
    out.temperature.push_back(std::move(column));
  }
  return out;
}

LogSampleReader::LogSampleReader(CsvReader& reader, const LogSpec& spec)
    : reader_(reader), spec_(spec), columns_(resolve_columns(spec, reader)) {
  const double to_dph = degrees_per_hour(spec.gyro_unit);
  for (std::size_t a = 0; a < columns_.gyro.size(); ++a) gyro_factor_.push_back(to_dph * spec.scaling.gyro_scale_of(a));
  if (spec.despike) {
    std::string why;
    if (!spec.despike->IsValid(&why)) throw UsageError(why);
    gyro_despikers_.assign(columns_.gyro.size(), Despiker(*spec.despike));
    temperature_despikers_.assign(columns_.temperature.size(), Despiker(*spec.despike));
    despiked_gyro_.assign(columns_.gyro.size(), 0);
    despiked_temperature_.assign(columns_.temperature.size(), 0);
  }
}

std::optional<CsvRow> LogSampleReader::next(LogSample& sample) {
  while (auto row = reader_.next()) {
    if (read(*row, sample)) {
      ++rows_;
      // After the row is kept: a dropped row never enters a despiker's window.
      bool replaced = false;
      for (std::size_t a = 0; a < gyro_despikers_.size(); ++a) {
        sample.gyro[a] = gyro_despikers_[a].push(sample.gyro[a], &replaced);
        despiked_gyro_[a] += replaced;
      }
      for (std::size_t c = 0; c < temperature_despikers_.size(); ++c) {
        sample.temperature[c] = temperature_despikers_[c].push(sample.temperature[c], &replaced);
        despiked_temperature_[c] += replaced;
      }
      return row;
    }
  }
  return std::nullopt;
}

bool LogSampleReader::read(const CsvRow& row, LogSample& sample) {
  const std::string& path = reader_.path();
  // Read every needed cell before judging the row, so one garbled cell drops the row
  // before its time is judged against the previous row's.
  auto cell = [&](std::size_t index, double& value) {
    const auto status = parse_number(row.cell(index), value);
    if (status == CellStatus::ok) return true;
    if (status == CellStatus::not_finite || status == CellStatus::out_of_range) {
      parse_cell(row.cell(index), path, row.line, index + 1);  // throws the one-line error
    }
    reader_.drop_garbled(row, index + 1,
                         row.cell(index).empty() ? std::string("empty cell, expected a number")
                                                 : fmt::format("'{}' is not a number", excerpt(row.cell(index))));
    return false;
  };
  TimeStamp stamp;
  if (columns_.time && !read_time(row, stamp)) return false;
  sample.gyro.resize(columns_.gyro.size());
  sample.temperature.resize(columns_.temperature.size());
  for (std::size_t a = 0; a < columns_.gyro.size(); ++a) {
    if (!cell(columns_.gyro[a], sample.gyro[a])) return false;
    sample.gyro[a] *= gyro_factor_[a];
  }
  for (std::size_t c = 0; c < columns_.temperature.size(); ++c) {
    if (!cell(columns_.temperature[c], sample.temperature[c])) return false;
    sample.temperature[c] = spec_.scaling.temperature_scale_of(c) * sample.temperature[c] +
                            spec_.scaling.temperature_offset_of(c);
  }
  check_physical_range(row, sample);
  if (!columns_.time) {
    sample.time = static_cast<double>(rows_) / *spec_.rate_hz;
    return true;
  }
  const std::string_view text = row.cell(*columns_.time);
  if (origin_) {
    const std::size_t column = *columns_.time + 1;
    if (stamp == previous_) throw DataError(path, row.line, column, fmt::format("time {} repeats the previous row's", excerpt(text)));
    if (stamp < previous_) {
      throw DataError(path, row.line, column, fmt::format("time goes backwards ({} after {})", excerpt(text), excerpt(previous_text_)));
    }
  } else {
    // The first kept row's stamp is the origin the others count from.
    origin_ = TimeOrigin{std::string(text), stamp.iso ? TimeUnit::s : spec_.time_unit, stamp};
  }
  previous_ = stamp;
  previous_text_.assign(text);
  sample.time = stamp.seconds_since(origin_->stamp);
  return true;
}

// A finite value beyond the physical range is no glitch of the link to drop but a wrong
// file, unit or scale: always an error, like NaN. Judged after unit and scaling, so a
// raw-count log read with its scale passes.
void LogSampleReader::check_physical_range(const CsvRow& row, const LogSample& sample) const {
  for (std::size_t a = 0; a < sample.gyro.size(); ++a) {
    if (plausible_rate(sample.gyro[a])) continue;
    throw DataError(reader_.path(), row.line, columns_.gyro[a] + 1,
                    fmt::format("gyro '{}' is {:.4g} °/h, beyond the physical range of ±{:.4g} °/h (10^5 °/s): "
                                "check --gyro-unit and --gyro-scale",
                                excerpt(row.cell(columns_.gyro[a])), sample.gyro[a], kMaxRateDph));
  }
  for (std::size_t c = 0; c < sample.temperature.size(); ++c) {
    const double t = sample.temperature[c];
    if (plausible_temperature(t)) continue;
    throw DataError(reader_.path(), row.line, columns_.temperature[c] + 1,
                    fmt::format("temperature '{}' is {:.4g} °C, beyond the physical range of {} to {} °C: "
                                "check --temp-scale and --temp-offset",
                                excerpt(row.cell(columns_.temperature[c])), t, kMinTemperatureC, kMaxTemperatureC));
  }
}

// Reads the time cell exactly; false when the row was dropped as garbled.
bool LogSampleReader::read_time(const CsvRow& row, TimeStamp& stamp) {
  const std::string& path = reader_.path();
  const std::size_t column = *columns_.time + 1;
  const std::string_view text = row.cell(*columns_.time);
  std::string problem;
  if (!parse_time_stamp(text, spec_.time_unit, stamp, &problem)) {
    double ignored = 0;
    const auto status = parse_number(text, ignored);
    if (status == CellStatus::not_finite) parse_cell(text, path, row.line, column);  // throws the one-line error
    // A number the time arithmetic cannot hold exactly is no serial-link glitch.
    if (status == CellStatus::ok || status == CellStatus::out_of_range) throw DataError(path, row.line, column, problem);
    reader_.drop_garbled(row, column, problem);
    return false;
  }
  if (!origin_) return true;
  if (stamp.iso != origin_->stamp.iso) {
    reader_.drop_garbled(row, column,
                         fmt::format("'{}': expected {} like the first row's ('{}')", excerpt(text),
                                     origin_->stamp.iso ? "an ISO 8601 time stamp" : "a number", excerpt(origin_->text)));
    return false;
  }
  return true;
}

ChamberLog read_chamber_log(const std::string& path, const LogSpec& spec, const StopToken& stop) {
  CsvReader reader(path, spec.csv);
  return read_chamber_log(reader, spec, stop);
}

ChamberLog read_chamber_log(CsvReader& reader, const LogSpec& spec, const StopToken& stop) {
  LogSampleReader samples(reader, spec);
  const LogColumns& columns = samples.columns();

  ChamberLog log;
  log.source = reader.path();
  log.gyro_names = columns.gyro_names;
  log.temperature_names = columns.temperature_names;
  log.gyro.resize(columns.gyro.size());
  log.temperature.resize(columns.temperature.size());

  LogSample sample;
  while (auto row = samples.next(sample)) {
    if ((log.time.size() & 0xFFF) == 0) stop.throw_if_requested("reading the log");
    log.time.push_back(sample.time);
    log.line.push_back(row->line);
    for (std::size_t a = 0; a < sample.gyro.size(); ++a) log.gyro[a].push_back(sample.gyro[a]);
    for (std::size_t c = 0; c < sample.temperature.size(); ++c) log.temperature[c].push_back(sample.temperature[c]);
  }
  reader.finish();
  log.time_origin = samples.time_origin();
  log.despiked_gyro = samples.despiked_gyro();
  log.despiked_temperature = samples.despiked_temperature();
  log.warnings = reader.warnings();
  return log;
}

}  // namespace thermodrift
