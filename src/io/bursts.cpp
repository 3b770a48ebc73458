#include "thermodrift/io/bursts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace thermodrift {

namespace {

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// [first row, end row) of each burst: rows joined by steps of at most `join` seconds.
std::vector<std::pair<std::size_t, std::size_t>> runs_of_rows(const ChamberLog& log, double join) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= log.rows(); ++i) {
    if (i == log.rows() || log.time[i] - log.time[i - 1] > join) {
      runs.emplace_back(begin, i);
      begin = i;
    }
  }
  return runs;
}

double join_seconds(const ChamberLog& log) {
  std::vector<double> steps;
  for (std::size_t i = 1; i < log.rows(); ++i) steps.push_back(log.time[i] - log.time[i - 1]);
  return std::max(10 * median(steps), 1.0);
}

}  // namespace

std::string BurstSummary::describe() const {
  return fmt::format("{} bursts of {:g} samples ({:.3g} s) every {:.4g} s", bursts, median_samples,
                     median_duration_s, period_s);
}

std::optional<BurstSummary> find_bursts(const ChamberLog& log, double warm_up_seconds) {
  if (log.rows() < 6 || log.bursts) return std::nullopt;
  const auto runs = runs_of_rows(log, join_seconds(log));
  if (runs.size() < 3) return std::nullopt;
  std::vector<double> samples, durations, gaps, period;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const auto [begin, end] = runs[k];
    samples.push_back(static_cast<double>(end - begin));
    durations.push_back(log.time[end - 1] - log.time[begin]);
    if (k > 0) {
      gaps.push_back(log.time[begin] - log.time[runs[k - 1].second - 1]);
      period.push_back(log.time[begin] - log.time[runs[k - 1].first]);
    }
  }
  const double duration = median(durations);
  // Bursts too short to warm up in, with longer gaps between them: otherwise the runs of
  // rows are segments of an ordinary log with a few dropouts, each warming up by itself.
  if (!(duration < warm_up_seconds) || !(median(gaps) > duration)) return std::nullopt;
  BurstSummary summary;
  summary.bursts = runs.size();
  summary.rows = log.rows();
  summary.median_samples = median(samples);
  summary.median_duration_s = duration;
  summary.period_s = median(period);
  return summary;
}

namespace {

// The log with each group of rows [begin, end) replaced by one row: the mean time, gyro
// and temperature of its rows, the file line of its first row.
ChamberLog means_of_groups(const ChamberLog& log, const std::vector<std::pair<std::size_t, std::size_t>>& groups) {
  ChamberLog out = without_rows(log);
  out.warnings = log.warnings;
  out.despiked_gyro = log.despiked_gyro;
  out.despiked_temperature = log.despiked_temperature;
  out.gyro.resize(log.gyro.size());
  out.temperature.resize(log.temperature.size());
  auto mean = [](const std::vector<double>& values, std::size_t begin, std::size_t end) {
    double sum = 0;
    for (std::size_t i = begin; i < end; ++i) sum += values[i];
    return sum / static_cast<double>(end - begin);
  };
  for (const auto& [begin, end] : groups) {
    out.time.push_back(mean(log.time, begin, end));
    for (std::size_t a = 0; a < log.gyro.size(); ++a) out.gyro[a].push_back(mean(log.gyro[a], begin, end));
    for (std::size_t c = 0; c < log.temperature.size(); ++c) {
      out.temperature[c].push_back(mean(log.temperature[c], begin, end));
    }
    out.line.push_back(log.line[begin]);
  }
  out.bursts = log.bursts;
  return out;
}

}  // namespace

ChamberLog collapse_bursts(const ChamberLog& log, const BurstSummary& bursts) {
  ChamberLog out = means_of_groups(log, runs_of_rows(log, join_seconds(log)));
  out.bursts = bursts;
  return out;
}

ChamberLog binned(const ChamberLog& log, double seconds) {
  std::vector<std::pair<std::size_t, std::size_t>> groups;
  if (log.rows() == 0) return log;
  const double start = log.time.front();
  for (std::size_t begin = 0; begin < log.rows();) {
    const double bin = std::floor((log.time[begin] - start) / seconds);
    std::size_t end = begin + 1;
    while (end < log.rows() && std::floor((log.time[end] - start) / seconds) == bin) ++end;
    groups.emplace_back(begin, end);
    begin = end;
  }
  return means_of_groups(log, groups);
}

ChamberLog collapse_if_bursts(ChamberLog log, double warm_up_seconds) {
  if (const auto bursts = find_bursts(log, warm_up_seconds)) return collapse_bursts(log, *bursts);
  return log;
}

}  // namespace thermodrift
