// fit --despike: isolated spikes of a log are replaced before anything else, counted, and
// the model keeps the filter so that evaluate and compensate read the log the same way.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(Despike, SpikesAreReplacedCountedAndKeptInTheModel) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 1 --min-temp 0 --max-temp 40 --soak 30 --seed 4 --out clean.csv").status, 0);
  // Three single-sample spikes of +500 °/h in gyro_x and one of +80 °C in temp_x.
  auto lines = split_lines(read_file(dir.file("clean.csv")));
  const std::vector<std::string> header = cells_of(lines[0]);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  auto bump = [&](std::size_t row, std::size_t index, double by) {
    auto cells = cells_of(lines[row]);
    cells[index] = std::to_string(std::stod(cells[index]) + by);
    lines[row] = join_cells(cells);
  };
  for (std::size_t row : {3000u, 7000u, 12000u}) bump(row, column("gyro_x"), 500);
  bump(9000, column("temp_x"), 80);
  std::string spiky;
  for (const auto& line : lines) spiky += line + "\n";
  dir.write("spiky.csv", spiky);

  const std::string fit = "fit --gyro gyro_x --temp temp_x --model linear ";
  ASSERT_EQ(run_thermodrift(dir, fit + "--data clean.csv --out clean.json").status, 0);
  ASSERT_EQ(run_thermodrift(dir, fit + "--data spiky.csv --out raw.json").status, 0);
  const auto despiked = run_thermodrift(dir, fit + "--data spiky.csv --despike --out despiked.json");
  ASSERT_EQ(despiked.status, 0) << despiked.err;
  EXPECT_NE(despiked.err.find("spiky.csv: despike replaced"), std::string::npos) << despiked.err;

  const auto model = nlohmann::json::parse(read_file(dir.file("despiked.json")));
  ASSERT_TRUE(model.contains("despike"));
  EXPECT_GE(model["despike"]["replaced_in_training"]["gyro"][0].get<int>(), 3);
  EXPECT_GE(model["despike"]["replaced_in_training"]["temperature"][0].get<int>(), 1);
  EXPECT_FALSE(nlohmann::json::parse(read_file(dir.file("raw.json"))).contains("despike"));
  // The spikes moved the fit; despiked, it is the clean log's again (near: the filter
  // also replaces a handful of noise samples beyond 6 sigmas).
  const auto coefficient = [&](const std::string& file, int k) {
    return nlohmann::json::parse(read_file(dir.file(file)))["axes"][0]["model"]["coefficients"][k].get<double>();
  };
  for (int k = 0; k < 2; ++k) {
    const double clean = coefficient("clean.json", k);
    EXPECT_LT(std::abs(coefficient("despiked.json", k) - clean), 0.2 * std::abs(coefficient("raw.json", k) - clean))
        << "coefficient " << k;
  }
  // evaluate and compensate read the spiky log with the model's filter, unasked.
  const auto compensated = run_thermodrift(dir, "compensate --model despiked.json --data spiky.csv --out c.csv");
  ASSERT_EQ(compensated.status, 0) << compensated.err;
  EXPECT_NE(compensated.err.find("despike replaced"), std::string::npos) << compensated.err;
  const auto evaluated = run_thermodrift(dir, "evaluate --model despiked.json --data spiky.csv --json");
  ASSERT_EQ(evaluated.status, 0) << evaluated.err;
  EXPECT_NE(evaluated.err.find("despike replaced"), std::string::npos) << evaluated.err;
}

}  // namespace
}  // namespace thermodrift::testing
