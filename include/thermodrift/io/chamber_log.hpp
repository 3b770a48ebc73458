// A temperature-chamber test log: time, one or more gyro axes (stored in °/h whatever
// the file's unit), one or more temperature channels (°C).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "thermodrift/io/csv_reader.hpp"
#include "thermodrift/io/despike.hpp"
#include "thermodrift/io/time_stamp.hpp"
#include "thermodrift/stop_token.hpp"

namespace thermodrift {

enum class GyroUnit { dph, dps, radps };

GyroUnit parse_gyro_unit(std::string_view name);  // "dph", "dps", "radps"; UsageError otherwise
std::string_view to_string(GyroUnit unit);
double degrees_per_hour(GyroUnit unit);  // factor from `unit` to °/h

// Physical ranges of a log's values in the library's units, after --gyro-unit and the
// scaling: a value beyond them is no reading of a gyro in a chamber but a corrupted cell,
// a wrong unit or a raw count read without its scale, and is a DataError at its cell
// (docs/data.md). Wide on purpose: 10^5 °/s is 50 times the fastest MEMS gyro's range.
inline constexpr double kMinTemperatureC = -273.15;  // absolute zero
inline constexpr double kMaxTemperatureC = 1000;
inline constexpr double kMaxRateDph = 3.6e8;  // |rate|: 10^5 °/s

// Within those ranges (false for NaN and infinities): the reader's test of a cell, and the
// field code's (Compensator, the exported header) test of a sample it is handed.
inline constexpr bool plausible_temperature(double celsius) {
  return celsius >= kMinTemperatureC && celsius <= kMaxTemperatureC;
}
inline constexpr bool plausible_rate(double dph) { return dph >= -kMaxRateDph && dph <= kMaxRateDph; }

// Raw log values to the library's units: °C = temperature_scale·raw + temperature_offset,
// °/h = degrees_per_hour(gyro_unit)·gyro_scale·raw. Each list holds one value for every
// column or one per column, in the order the columns are named; empty means the default
// (scale 1, offset 0).
struct LogScaling {
  std::vector<double> temperature_scale;
  std::vector<double> temperature_offset;
  std::vector<double> gyro_scale;

  bool is_default() const;  // no value other than 1 (scales) and 0 (offsets)
  // The value for one column (0-based among the temperature or the gyro columns).
  double temperature_scale_of(std::size_t column) const;
  double temperature_offset_of(std::size_t column) const;
  double gyro_scale_of(std::size_t column) const;
  // Throws UsageError when a list is neither one value nor one per column (a count of 0:
  // not known yet, not checked), a value is not finite or a scale is 0.
  void check(std::size_t gyro_columns, std::size_t temperature_columns) const;
};

// Which columns of a log hold what, and in what units. A column is named by its header
// name or by its 1-based index.
struct LogSpec {
  std::optional<std::string> time_column;         // else rate_hz gives the time
  TimeUnit time_unit = TimeUnit::s;               // of numbers in the time column (ISO 8601 stamps need none)
  std::optional<double> rate_hz;                  // sampling rate when there is no time column
  std::vector<std::string> gyro_columns;          // empty: every header name starting "gyro"
  std::vector<std::string> temperature_columns;   // empty: every header name starting "temp"
  GyroUnit gyro_unit = GyroUnit::dph;
  LogScaling scaling;                             // raw counts to °C and °/h
  std::optional<DespikeOptions> despike;          // replace isolated outliers (off: nullopt)
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
// when a named column is not there, UsageError when the spec is incomplete or its
// scaling does not fit the columns (LogScaling::check).
LogColumns resolve_columns(const LogSpec& spec, const CsvReader& reader);

// Where a log's time starts: its first row's time stamp. Times in a log are seconds since
// it, so no 1.7e9-sized epoch reaches the arithmetic downstream.
struct TimeOrigin {
  std::string text;               // the first row's time cell as written
  TimeUnit unit = TimeUnit::s;    // unit it was read in (an ISO 8601 stamp: s since 1970 UTC)
  TimeStamp stamp;                // exactly
};

// What a burst log's bursts were (io/bursts.hpp): each burst's mean is one row of the log.
struct BurstSummary {
  std::size_t bursts = 0;
  std::size_t rows = 0;               // rows of the file they hold
  double median_samples = 0;          // rows per burst
  double median_duration_s = 0;       // first to last row of a burst
  double period_s = 0;                // median step between burst means
  // Steps up to this many seconds join burst means (two bursts missed in a row: a gap).
  double gap_seconds() const { return 2.5 * period_s; }
  std::string describe() const;       // "72 bursts of 250 samples (5 s) every 300 s"
};

struct ChamberLog {
  std::string source;                             // file it was read from
  std::vector<double> time;                       // s since time_origin (or row / rate), strictly increasing
  std::optional<TimeOrigin> time_origin;          // absent without a time column
  std::vector<std::string> gyro_names;
  std::vector<std::vector<double>> gyro;          // [axis][row], °/h
  std::vector<std::string> temperature_names;
  std::vector<std::vector<double>> temperature;   // [channel][row], °C
  std::vector<std::size_t> line;                  // file line of each row
  std::vector<std::string> warnings;              // skipped banners, dropped cut-short rows
  std::optional<BurstSummary> bursts;             // set when each row is a burst's mean
  // With LogSpec::despike: samples replaced per gyro axis and per temperature channel.
  std::vector<std::size_t> despiked_gyro, despiked_temperature;

  std::size_t rows() const { return time.size(); }
  std::size_t axes() const { return gyro.size(); }
};

// Reads a whole log. Every malformed cell, row or time stamp is a DataError naming
// file, line and column. `stop` is asked every 4096 rows (Interrupted).
ChamberLog read_chamber_log(const std::string& path, const LogSpec& spec, const StopToken& stop = {});
// The same from an open reader (a stream, say).
ChamberLog read_chamber_log(CsvReader& reader, const LogSpec& spec, const StopToken& stop = {});

// The median step between a log's rows, s (1 for a log of fewer than two rows).
double median_step(const ChamberLog& log);

// A log with no rows and `log`'s source, time origin and column names: what a log made
// from it (a slice, burst means, a history before it) starts from.
ChamberLog without_rows(const ChamberLog& log);

// Rows [begin, end) of a log, as a log of their own (a held-out cycle, say).
ChamberLog slice_rows(const ChamberLog& log, std::size_t begin, std::size_t end);

// A log cut from a running recording, with a history before it in which each temperature
// channel followed the straight line fitted (least squares) to its first `fit_seconds`,
// held within that channel's range over the log: `span_seconds` of rows every max(the
// log's median step, 1 s), the gyro columns holding their first value, line 0. A model
// streamed over it starts the log's own rows with its lags where a unit that had been
// following its initial rate leaves them, not in equilibrium at the first row
// (`evaluate --log-start running`). The log's rows follow unchanged.
inline constexpr double kRampHistorySeconds = 21600;  // four times the longest lag a search chooses
inline constexpr double kRampFitSeconds = 300;
ChamberLog with_ramp_history(const ChamberLog& log, double span_seconds = kRampHistorySeconds,
                             double fit_seconds = kRampFitSeconds);

struct LogSample {
  double time = 0;                  // s since the first kept row's time (or row / rate)
  std::vector<double> gyro;         // °/h
  std::vector<double> temperature;  // °C
};

// Reads a log's rows one at a time, as samples: the one reader behind read_chamber_log
// and the streaming `thermodrift compensate`, so both read every row alike. Garbled rows
// are dropped (see CsvOptions); NaN/Inf, a value beyond the physical range, a time stamp
// out of order or in the other form (number / ISO 8601) than the first row's are
// DataErrors naming line and column.
class LogSampleReader {
 public:
  // Resolves the columns (resolve_columns); `reader` must outlive this.
  LogSampleReader(CsvReader& reader, const LogSpec& spec);

  const LogColumns& columns() const { return columns_; }
  const std::optional<TimeOrigin>& time_origin() const { return origin_; }
  std::size_t rows() const { return rows_; }  // rows kept so far
  // With spec.despike: samples replaced so far per gyro column and per temperature column.
  const std::vector<std::size_t>& despiked_gyro() const { return despiked_gyro_; }
  const std::vector<std::size_t>& despiked_temperature() const { return despiked_temperature_; }

  // The next kept row, its cells read into `sample`; nothing at the end of the file.
  std::optional<CsvRow> next(LogSample& sample);

 private:
  bool read(const CsvRow& row, LogSample& sample);
  bool read_time(const CsvRow& row, TimeStamp& stamp);
  void check_physical_range(const CsvRow& row, const LogSample& sample) const;

  CsvReader& reader_;
  LogSpec spec_;
  LogColumns columns_;
  std::vector<double> gyro_factor_;  // °/h per raw unit, per gyro column
  std::vector<Despiker> gyro_despikers_, temperature_despikers_;
  std::vector<std::size_t> despiked_gyro_, despiked_temperature_;
  std::optional<TimeOrigin> origin_;
  TimeStamp previous_;
  std::string previous_text_;
  std::size_t rows_ = 0;
};

}  // namespace thermodrift
