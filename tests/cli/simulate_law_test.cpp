// thermodrift simulate --law: a unit of the law family through a drawn programme, written
// with the usual columns (and, with --internal-states, the law's true regressors); an
// unknown profile is a usage error of one line.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "thermodrift/sim/chamber_run.hpp"
#include "thermodrift/sim/law_family.hpp"

namespace thermodrift {
namespace {

using testing::CommandResult;
using testing::read_file;
using testing::split_lines;
using testing::TempDir;

using testing::run_thermodrift;

std::string chamber_run_header() {
  std::string header;
  for (std::string_view name : sim::chamber_run_columns) header += (header.empty() ? "" : ",") + std::string(name);
  return header;
}

// The lines of a staircase run of law 5 (one cycle) written with `options`.
std::vector<std::string> staircase_lines(const TempDir& dir, const std::string& options) {
  const auto result = run_thermodrift(dir, "simulate --law 5 --profile staircase --cycles 1 --out x.csv" + options);
  EXPECT_EQ(result.status, 0) << result.err;
  return split_lines(read_file(dir.file("x.csv")));
}

TEST(SimulateLaw, WritesTheChamberRunColumns) {
  TempDir dir;
  const auto lines = staircase_lines(dir, "");
  ASSERT_GT(lines.size(), 3600u);
  EXPECT_EQ(lines.front(), chamber_run_header());
  EXPECT_EQ(std::count(lines.back().begin(), lines.back().end(), ','), 10);
}

TEST(SimulateLaw, DescribePrintsTheDrawnLawOnStderr) {
  TempDir dir;
  const auto result = run_thermodrift(dir, "simulate --law 5 --profile wander --describe --out x.csv");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_TRUE(result.err.starts_with("law 5: range")) << result.err;
  EXPECT_NE(result.err.find("  z: chain"), std::string::npos) << result.err;
  // Law 5: y has a play, z a memory; their constants are printed with them.
  EXPECT_NE(result.err.find("hysteresis play 0.07 (W "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("hysteresis memory 0.13 (τ "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(" °C/min); turn-on"), std::string::npos) << result.err;
}

std::vector<double> numbers(const std::string& line) {
  std::vector<double> out;
  for (const std::string& cell : testing::cells_of(line)) out.push_back(std::stod(cell));
  return out;
}

// The law's regressors written beside the log are the states its true drift is made of: the
// drawn coefficients on them give each axis' drift column back.
TEST(SimulateLaw, InternalStatesAreTheRegressorsOfTheTrueDrift) {
  TempDir dir;
  const auto lines = staircase_lines(dir, " --internal-states");
  ASSERT_GT(lines.size(), 3600u);
  const auto names = sim::law_regressor_names();
  std::string header = chamber_run_header();
  for (const char* axis : sim::kAxisNames) {
    for (std::size_t k = 1; k < sim::kLawRegressors; ++k) header += fmt::format(",law_{}_{}", axis, names[k]);
  }
  EXPECT_EQ(lines.front(), header);
  const sim::UnitLaw unit = sim::draw_unit(5);
  const std::size_t first = sim::chamber_run_columns.size();
  double largest = 0, worst = 0;
  for (std::size_t i = 1; i < lines.size(); i += 97) {
    const std::vector<double> row = numbers(lines[i]);
    ASSERT_EQ(row.size(), first + 3 * (sim::kLawRegressors - 1)) << lines[i];
    for (std::size_t a = 0; a < 3; ++a) {
      const auto coefficients = sim::law_coefficients(unit.axes[a]);
      double drift = coefficients[0];
      for (std::size_t k = 1; k < sim::kLawRegressors; ++k) {
        drift += coefficients[k] * row[first + a * (sim::kLawRegressors - 1) + k - 1];
      }
      const double written = row[8 + a];  // drift_x, drift_y, drift_z
      largest = std::max(largest, std::abs(written));
      worst = std::max(worst, std::abs(drift - written));
    }
  }
  EXPECT_GT(largest, 0.1) << "a drift to compare";
  EXPECT_LT(worst, 1e-5) << "the regressors (9 significant digits) give the drift column back";
}

TEST(SimulateLaw, AnUnknownProfileExitsTwoWithOneLine) {
  TempDir dir;
  const auto result = run_thermodrift(dir, "simulate --law 5 --profile nonsense --out x.csv");
  EXPECT_EQ(result.status, 2);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_TRUE(result.err.starts_with("thermodrift: ")) << result.err;
  EXPECT_NE(result.err.find("nonsense"), std::string::npos) << result.err;
  EXPECT_EQ(dir.entries(), std::vector<std::string>{}) << "no output file on failure";
}

}  // namespace
}  // namespace thermodrift
