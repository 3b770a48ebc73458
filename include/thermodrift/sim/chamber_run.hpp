// The result of one simulated chamber test: the log a real test would record, plus the
// true drift beside it.
#pragma once

#include <array>
#include <optional>
#include <cstddef>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/stop_token.hpp"
#include "thermodrift/sim/options.hpp"

namespace thermodrift::sim {

// Columns of every run, in this order; with record_internal_states the state columns
// (internal_state_columns) follow.
inline constexpr std::array<std::string_view, 11> chamber_run_columns = {
    "time_s", "temp_chamber", "temp_x", "temp_y", "temp_z", "gyro_x",
    "gyro_y", "gyro_z",       "drift_x", "drift_y", "drift_z"};
// The same names by role, axis by axis (x, y, z): what reading a written run needs.
inline constexpr std::string_view time_column = "time_s";
inline constexpr std::array<std::string_view, 3> gyro_columns = {"gyro_x", "gyro_y", "gyro_z"};
inline constexpr std::array<std::string_view, 3> temperature_columns = {"temp_x", "temp_y", "temp_z"};
inline constexpr std::array<std::string_view, 3> drift_columns = {"drift_x", "drift_y", "drift_z"};
inline constexpr std::array<std::string_view, 9> internal_state_columns = {
    "coil_x",     "coil_y",     "coil_z",     "gradient_x",  "gradient_y",
    "gradient_z", "hysteresis_x", "hysteresis_y", "hysteresis_z"};

struct ChamberRun {
  std::vector<std::string> column_names;       // see chamber_run_columns
  std::vector<std::vector<double>> columns;    // column-major, one vector per name
  double rate_hz = 1.0;                        // sample rate; row k is at time k / rate_hz
  std::vector<double> cycle_start_s;           // time at which each cycle starts

  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  // The column called `name`; throws UsageError if there is none.
  const std::vector<double>& column(std::string_view name) const;
  // Times at which each cycle starts (the first is 0): cycle i is [start_i, start_i+1).
  const std::vector<double>& cycle_boundaries() const { return cycle_start_s; }
  // Row index at which each cycle starts.
  std::vector<std::size_t> cycle_start_rows() const;

  // Variance, per axis (x, y, z), of the noise (gyro - drift) left after a trailing
  // moving average over `window_s` seconds: what no drift model can remove from data
  // smoothed that way. Computed empirically from this run's noise series, over the rows
  // where the window is full, around the series' mean (a model's intercept absorbs a
  // constant). A window shorter than one sample means no smoothing. From `first_row` on
  // only: the floor of a held-out part (the smoothing still sees the rows before it).
  std::array<double, 3> noise_floor(double window_s, std::size_t first_row = 0) const;
};

// The columns a log written by write_csv (`thermodrift simulate`) holds the true drift
// of each gyro column in: drift_<suffix> for gyro_<suffix>. Nothing when a gyro column is
// not named so (a log from a chamber, not from the simulator).
std::optional<std::vector<std::string>> true_drift_columns(const std::vector<std::string>& gyro_names);

// How to read a log write_csv wrote: its time, gyro and temperature columns by name
// (the chamber air and the true drift are not inputs).
LogSpec log_spec();

// The run as the log thermodrift reads (time_s; gyro_x/y/z in °/h; temp_x/y/z, one per
// axis), without writing it out: line numbers as write_csv would give them.
ChamberLog to_chamber_log(const ChamberRun& run);

// The same quantity predicted from the noise model alone: white noise σ²/w, plus the
// Gauss-Markov bias variance reduced by the window, plus the quantization error, which
// with carried remainders averages as (r_k - r_k-w)/(w·dt). Use to check a run against
// its options, or when no run is at hand.
double expected_noise_floor(const NoiseOptions& noise, double rate_hz, double window_s);

// Writes a header row and one row per sample. Time is written in the shortest form that
// reads back to the same double; the other values with 9 significant digits, which is
// exact for the quantized gyro and temperature outputs.
void write_csv(const ChamberRun& run, std::ostream& out, const StopToken& stop = {});

}  // namespace thermodrift::sim
