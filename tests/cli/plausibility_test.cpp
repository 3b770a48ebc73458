// Finite but absurd values: a data error at the cell in a log, a refused model file, and
// never a model written that its own evaluate would refuse (issue 18: a gyro of 1e300 gave
// "target_scale": null or an intercept of 5e295 with exit 0).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

using testing::contains;

// The simulated log with line `line` (1-based, the header is line 1) given `cell` in
// column `column` (0-based).
std::string with_cell(const std::string& log, std::size_t line, std::size_t column, const std::string& cell) {
  auto lines = split_lines(log);
  auto cells = cells_of(lines.at(line - 1));
  cells.at(column) = cell;
  lines.at(line - 1) = join_cells(cells);
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  return text;
}

TEST(Plausibility, AbsurdLogValuesAreDataErrorsAndNothingIsWritten) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  const std::string log = read_file(dir.file("log.csv"));
  const auto header = cells_of(split_lines(log).front());
  const auto column_of = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::string gyro_x = std::to_string(column_of("gyro_x") + 1), temp_x = std::to_string(column_of("temp_x") + 1);
  dir.write("gyro.csv", with_cell(log, 40, column_of("gyro_x"), "1e300"));
  dir.write("temp.csv", with_cell(log, 41, column_of("temp_x"), "1e300"));
  for (const std::string model : {"linear", "svr --evaluations 4"}) {
    for (const auto& [file, where] : {std::pair{"gyro.csv", ":40:" + gyro_x + ": gyro '1e300'"},
                                      std::pair{"temp.csv", ":41:" + temp_x + ": temperature '1e300'"}}) {
      SCOPED_TRACE(file + (" " + model));
      const auto fit = run_thermodrift(dir, std::string("fit --data ") + file +
                                                " --gyro gyro_x --temp temp_x --out m.json --model " + model);
      EXPECT_EQ(fit.status, 3) << fit.err;
      EXPECT_TRUE(contains(fit.err, file + where)) << fit.err;
      EXPECT_TRUE(contains(fit.err, "beyond the physical range")) << fit.err;
      EXPECT_EQ(split_lines(fit.err).size(), 1u) << fit.err;
      EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
    }
  }
  // compensate reads rows by the same reader: refused too, nothing written.
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json").status, 0);
  const auto compensate = run_thermodrift(dir, "compensate --model m.json --data temp.csv --out c.csv");
  EXPECT_EQ(compensate.status, 3) << compensate.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv")));
}

TEST(Plausibility, AModelWithAbsurdNumbersIsRefusedAtLoad) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json").status, 0);
  std::string text = read_file(dir.file("m.json"));
  const auto at = text.find("\"intercept\": ");
  ASSERT_NE(at, std::string::npos);
  const auto end = text.find_first_of(",\n}", at + 13);
  text.replace(at + 13, end - at - 13, "1e308");
  dir.write("huge.json", text);
  for (const std::string command : {"evaluate --model huge.json --data log.csv",
                                    "compensate --model huge.json --data log.csv --out c.csv",
                                    "export --model huge.json --out m.h"}) {
    SCOPED_TRACE(command);
    const auto result = run_thermodrift(dir, command);
    EXPECT_EQ(result.status, 3) << result.err;
    EXPECT_TRUE(contains(result.err, "huge.json: axis 1: model.intercept is 1e+308, beyond")) << result.err;
    EXPECT_EQ(split_lines(result.err).size(), 1u) << result.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.h")));
  // Within ±1e12 but no temperature: a reference of 1e11 °C made compensate write 1.6e12 °/h.
  std::string hot = read_file(dir.file("m.json"));
  const auto reference = hot.find("\"reference_temperature\": ");
  ASSERT_NE(reference, std::string::npos);
  const auto value = reference + 25;
  hot.replace(value, hot.find_first_of(",\n}", value) - value, "1e11");
  dir.write("hot.json", hot);
  const auto result = run_thermodrift(dir, "compensate --model hot.json --data log.csv --out c.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  EXPECT_TRUE(contains(result.err, "reference temperature 1e+11 °C is beyond -273.15..1000 °C")) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv")));
}

}  // namespace
}  // namespace thermodrift::testing
