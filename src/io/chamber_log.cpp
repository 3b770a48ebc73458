#include "thermodrift/io/chamber_log.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
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

std::size_t find_column(const std::string& name, const CsvReader& reader, const char* role) {
  for (std::size_t i = 0; i < reader.header().size(); ++i) {
    if (reader.header()[i] == name) return i;
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
                  fmt::format("no {} column named '{}' (columns: {})", role, name,
                              fmt::join(reader.header(), ", ")));
}

std::vector<std::size_t> columns_with_prefix(const CsvReader& reader, std::string_view prefix) {
  std::vector<std::size_t> found;
  for (std::size_t i = 0; i < reader.header().size(); ++i) {
    if (reader.header()[i].starts_with(prefix)) found.push_back(i);
  }
  return found;
}

}  // namespace

LogColumns resolve_columns(const LogSpec& spec, const CsvReader& reader) {
  LogColumns columns;
  if (spec.time_column) {
    columns.time = find_column(*spec.time_column, reader, "time");
  } else if (!spec.rate_hz) {
    for (const char* name : {"time_s", "time", "t"}) {
      for (std::size_t i = 0; i < reader.header().size(); ++i) {
        if (!columns.time && reader.header()[i] == name) columns.time = i;
      }
    }
    if (!columns.time) {
      throw UsageError(fmt::format("{}: no time column found; name one with --time or give the "
                                   "sampling rate with --rate",
                                   reader.path()));
    }
  } else if (!(*spec.rate_hz > 0) || !std::isfinite(*spec.rate_hz)) {
    throw UsageError(fmt::format("--rate must be a positive number of hertz, not {}", *spec.rate_hz));
  }

  if (spec.gyro_columns.empty()) {
    columns.gyro = columns_with_prefix(reader, "gyro");
    if (columns.gyro.empty()) {
      throw UsageError(fmt::format("{}: no column named gyro*; name the gyro columns with --gyro",
                                   reader.path()));
    }
  } else {
    for (const auto& name : spec.gyro_columns) columns.gyro.push_back(find_column(name, reader, "gyro"));
  }
  if (spec.temperature_columns.empty()) {
    columns.temperature = columns_with_prefix(reader, "temp");
    if (columns.temperature.empty()) {
      throw UsageError(fmt::format(
          "{}: no column named temp*; name the temperature columns with --temp", reader.path()));
    }
    // Found by name, channels beyond one per axis would be paired with the axes by their
    // order in the file (a chamber column first would feed the first axis): ask instead.
    if (columns.temperature.size() != 1 && columns.temperature.size() != columns.gyro.size()) {
      std::vector<std::string> names;
      for (auto index : columns.temperature) names.push_back(column_label(reader, index));
      throw UsageError(fmt::format("{}: {} temp* columns ({}) for {} gyro axes; name one for all axes or one "
                                   "per axis with --temp (further columns serve grad terms)",
                                   reader.path(), names.size(), fmt::join(names, ","), columns.gyro.size()));
    }
  } else {
    for (const auto& name : spec.temperature_columns) {
      columns.temperature.push_back(find_column(name, reader, "temperature"));
    }
  }
  for (auto index : columns.gyro) columns.gyro_names.push_back(column_label(reader, index));
  for (auto index : columns.temperature) {
    columns.temperature_names.push_back(column_label(reader, index));
  }
  return columns;
}

void check_time_order(double previous, double current, const std::string& file, std::size_t line,
                      std::size_t column) {
  if (std::isnan(previous)) return;
  if (current == previous) {
    throw DataError(file, line, column, fmt::format("time {} repeats the previous row's", current));
  }
  if (current < previous) {
    throw DataError(file, line, column,
                    fmt::format("time goes backwards ({} after {})", current, previous));
  }
}

ChamberLog slice_rows(const ChamberLog& log, std::size_t begin, std::size_t end) {
  end = std::min(end, log.rows());
  begin = std::min(begin, end);
  auto cut = [&](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(begin),
                               v.begin() + static_cast<std::ptrdiff_t>(end));
  };
  ChamberLog part;
  part.source = log.source;
  part.time = cut(log.time);
  part.gyro_names = log.gyro_names;
  part.temperature_names = log.temperature_names;
  for (const auto& g : log.gyro) part.gyro.push_back(cut(g));
  for (const auto& t : log.temperature) part.temperature.push_back(cut(t));
  part.line.assign(log.line.begin() + static_cast<std::ptrdiff_t>(begin),
                   log.line.begin() + static_cast<std::ptrdiff_t>(end));
  return part;
}

bool read_sample(CsvReader& reader, const CsvRow& row, const LogColumns& columns, const LogSpec& spec,
                 std::size_t row_index, double previous_time, LogSample& sample) {
  const std::string& path = reader.path();
  // Read every needed cell before judging the row, so one garbled cell drops the row.
  auto cell = [&](std::size_t index, double& value) {
    const auto status = parse_number(row.cell(index), value);
    if (status == CellStatus::ok) return true;
    if (status == CellStatus::not_finite || status == CellStatus::out_of_range) {
      parse_cell(row.cell(index), path, row.line, index + 1);  // throws the one-line error
    }
    reader.drop_garbled(row, index + 1,
                        row.cell(index).empty() ? std::string("empty cell, expected a number")
                                                : fmt::format("'{}' is not a number", row.cell(index)));
    return false;
  };
  if (columns.time) {
    if (!cell(*columns.time, sample.time)) return false;
  } else {
    sample.time = static_cast<double>(row_index) / *spec.rate_hz;
  }
  const double to_dph = degrees_per_hour(spec.gyro_unit);
  sample.gyro.resize(columns.gyro.size());
  sample.temperature.resize(columns.temperature.size());
  for (std::size_t a = 0; a < columns.gyro.size(); ++a) {
    if (!cell(columns.gyro[a], sample.gyro[a])) return false;
    sample.gyro[a] *= to_dph;
  }
  for (std::size_t c = 0; c < columns.temperature.size(); ++c) {
    if (!cell(columns.temperature[c], sample.temperature[c])) return false;
  }
  if (columns.time) check_time_order(previous_time, sample.time, path, row.line, *columns.time + 1);
  return true;
}

ChamberLog read_chamber_log(const std::string& path, const LogSpec& spec) {
  CsvReader reader(path, spec.csv);
  return read_chamber_log(reader, spec);
}

ChamberLog read_chamber_log(CsvReader& reader, const LogSpec& spec) {
  const std::string& path = reader.path();
  const LogColumns columns = resolve_columns(spec, reader);

  ChamberLog log;
  log.source = path;
  log.gyro_names = columns.gyro_names;
  log.temperature_names = columns.temperature_names;
  log.gyro.resize(columns.gyro.size());
  log.temperature.resize(columns.temperature.size());

  LogSample sample;
  double previous_time = std::nan("");
  while (auto row = reader.next()) {
    if (!read_sample(reader, *row, columns, spec, log.time.size(), previous_time, sample)) continue;
    previous_time = sample.time;
    log.time.push_back(sample.time);
    log.line.push_back(row->line);
    for (std::size_t a = 0; a < sample.gyro.size(); ++a) log.gyro[a].push_back(sample.gyro[a]);
    for (std::size_t c = 0; c < sample.temperature.size(); ++c) log.temperature[c].push_back(sample.temperature[c]);
  }
  reader.finish();
  log.warnings = reader.warnings();
  return log;
}

}  // namespace thermodrift
