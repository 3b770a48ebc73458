#include "thermodrift/sim/chamber_run.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "thermodrift/error.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::sim {
namespace {

std::vector<double> parse_row(const std::string& line) {
  std::vector<double> values;
  std::stringstream cells(line);
  std::string cell;
  while (std::getline(cells, cell, ',')) values.push_back(std::stod(cell));
  return values;
}

TEST(WriteCsv, HeaderRowCountAndRoundTrip) {
  SimulatorOptions options;
  options.cycles = 1;
  options.rate_hz = 3.0;  // non-integer times
  const ChamberRun run = simulate(options);
  std::ostringstream out;
  write_csv(run, out);

  std::istringstream in(out.str());
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line,
            "time_s,temp_chamber,temp_x,temp_y,temp_z,gyro_x,gyro_y,gyro_z,drift_x,drift_y,drift_z");
  std::size_t row = 0;
  while (std::getline(in, line)) {
    const std::vector<double> values = parse_row(line);
    ASSERT_EQ(values.size(), 11u) << "row " << row;
    EXPECT_EQ(values[0], run.columns[0][row]) << "time reads back exactly";
    for (std::size_t c = 1; c < values.size(); ++c) {
      const double original = run.columns[c][row];
      ASSERT_NEAR(values[c], original, 1e-8 * std::max(1.0, std::abs(original))) << "row " << row << " col " << c;
    }
    ++row;
  }
  EXPECT_EQ(row, run.rows());
  EXPECT_EQ(row, 22800u * 3);
}

TEST(ChamberRun, UnknownColumnIsAUsageError) {
  ChamberRun run = simulate(SimulatorOptions{});
  EXPECT_THROW(run.column("gyro_w"), UsageError);
  EXPECT_THROW(run.noise_floor(-1.0), UsageError);
}

TEST(NoiseFloor, MatchesTheNoiseModelAndFallsWithTheWindow) {
  const ChamberRun run = simulate(SimulatorOptions{});
  const NoiseOptions noise;
  double previous = INFINITY;
  for (double window_s : {0.0, 10.0, 100.0, 1000.0}) {
    const std::array<double, 3> floor = run.noise_floor(window_s);
    const double expected = expected_noise_floor(noise, 1.0, window_s);
    // The Gauss-Markov bias has few independent stretches in 12.7 h: loose at long windows.
    const double tolerance = window_s >= 1000.0 ? 0.5 : 0.15;
    for (double variance : floor) {
      EXPECT_NEAR(variance, expected, tolerance * expected) << "window " << window_s;
      EXPECT_LT(variance, previous);
    }
    previous = *std::min_element(floor.begin(), floor.end());
  }
  // At the paper's 100-s smoothing: white 0.18²/100 plus most of the 0.0107² bias variance.
  EXPECT_NEAR(expected_noise_floor(noise, 1.0, 100.0), 4.3e-4, 0.2e-4);
}

// From a first row on, unsmoothed: the plain variance of that part's noise; and the
// log view of the run holds the same samples.
TEST(NoiseFloor, FromAFirstRowIsThatPartsVariance) {
  SimulatorOptions options;
  options.cycles = 1;
  const ChamberRun run = simulate(options);
  const std::size_t first = run.rows() / 2;
  const auto& gyro = run.column("gyro_y");
  const auto& drift = run.column("drift_y");
  double sum = 0, squares = 0;
  for (std::size_t r = first; r < run.rows(); ++r) sum += gyro[r] - drift[r];
  const double mean = sum / static_cast<double>(run.rows() - first);
  for (std::size_t r = first; r < run.rows(); ++r) squares += std::pow(gyro[r] - drift[r] - mean, 2);
  EXPECT_NEAR(run.noise_floor(0.0, first)[1], squares / static_cast<double>(run.rows() - first), 1e-12);
  EXPECT_NE(run.noise_floor(0.0, first)[1], run.noise_floor(0.0)[1]);
  EXPECT_THROW(run.noise_floor(100.0, run.rows() - 1), UsageError);

  const ChamberLog log = to_chamber_log(run);
  ASSERT_EQ(log.rows(), run.rows());
  EXPECT_EQ(log.gyro.at(1), gyro);
  EXPECT_EQ(log.temperature.at(2), run.column("temp_z"));
  EXPECT_EQ(log.line.back(), run.rows() + 1);
}

TEST(NoiseFloor, WhiteOnlyFloorIsVarianceOverWindow) {
  NoiseOptions white_only;
  white_only.bias_instability_dph = 0.0;
  white_only.quantization_arcsec = 0.0;
  const double sigma2 = std::pow(white_only.angle_random_walk_deg_per_sqrt_h * 60.0, 2);
  EXPECT_NEAR(expected_noise_floor(white_only, 1.0, 100.0), sigma2 / 100.0, 1e-15);
  EXPECT_NEAR(expected_noise_floor(white_only, 10.0, 100.0), sigma2 * 10.0 / 1000.0, 1e-15);
}

}  // namespace
}  // namespace thermodrift::sim
