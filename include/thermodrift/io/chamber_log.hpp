// A temperature-chamber test log: time, one or more gyro axes (stored in °/h whatever
// the file's unit), one or more temperature channels (°C).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "thermodrift/io/csv_reader.hpp"

namespace thermodrift {

enum class GyroUnit { dph, dps, radps };

GyroUnit parse_gyro_unit(std::string_view name);  // "dph", "dps", "radps"; UsageError otherwise
std::string_view to_string(GyroUnit unit);
double degrees_per_hour(GyroUnit unit);  // factor from `unit` to °/h

// Which columns of a log hold what. A column is named by its header name or by its
// 1-based index.
struct LogSpec {
  std::optional<std::string> time_column;         // seconds; else rate_hz gives the time
  std::optional<double> rate_hz;                  // sampling rate when there is no time column
  std::vector<std::string> gyro_columns;          // empty: every header name starting "gyro"
  std::vector<std::string> temperature_columns;   // empty: every header name starting "temp"
  GyroUnit gyro_unit = GyroUnit::dph;
  CsvOptions csv;                                 // tolerance for garbled rows
};

// Column positions (0-based) resolved against one file's header.
struct LogColumns {
  std::optional<std::size_t> time;
  std::vector<std::size_t> gyro;
  std::vector<std::size_t> temperature;
  std::vector<std::string> gyro_names;         // header names, or "column N" without a header
  std::vector<std::string> temperature_names;
};

// Resolves `spec` against the reader's header. Throws DataError naming the header line
// when a named column is not there, UsageError when the spec is incomplete.
LogColumns resolve_columns(const LogSpec& spec, const CsvReader& reader);

struct ChamberLog {
  std::string source;                             // file it was read from
  std::vector<double> time;                       // s, strictly increasing
  std::vector<std::string> gyro_names;
  std::vector<std::vector<double>> gyro;          // [axis][row], °/h
  std::vector<std::string> temperature_names;
  std::vector<std::vector<double>> temperature;   // [channel][row], °C
  std::vector<std::size_t> line;                  // file line of each row
  std::vector<std::string> warnings;              // skipped banners, dropped cut-short rows

  std::size_t rows() const { return time.size(); }
  std::size_t axes() const { return gyro.size(); }
};

// Reads a whole log. Every malformed cell, row or time stamp is a DataError naming
// file, line and column.
ChamberLog read_chamber_log(const std::string& path, const LogSpec& spec);
// The same from an open reader (a stream, say).
ChamberLog read_chamber_log(CsvReader& reader, const LogSpec& spec);

// Rows [begin, end) of a log, as a log of their own (a held-out cycle, say).
ChamberLog slice_rows(const ChamberLog& log, std::size_t begin, std::size_t end);

// Reads the cells `columns` name from one row into time, gyro (°/h) and temperature
// values. Returns false when the row was dropped as garbled (see CsvOptions); throws
// DataError for NaN/Inf and, through check_time_order, for time out of order.
// `row_index` counts the rows kept so far (time = row_index / rate without a time column).
struct LogSample {
  double time = 0;
  std::vector<double> gyro;
  std::vector<double> temperature;
};
bool read_sample(CsvReader& reader, const CsvRow& row, const LogColumns& columns, const LogSpec& spec,
                 std::size_t row_index, double previous_time, LogSample& sample);

// Checks one row's time stamp against the previous one (NaN for the first row); throws
// DataError when time goes backwards or repeats. Shared by the whole-file and the
// streaming readers so both say the same.
void check_time_order(double previous, double current, const std::string& file, std::size_t line,
                      std::size_t column);

}  // namespace thermodrift
