// `--identify` on fit (and, through the same option, report and demo): the identification
// `--features auto` uses is the one asked for, and the model file says which.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(Identify, FitUsesTheThermalNodeByDefaultAndTheGreedySearchWhenAsked) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.25 --seed 5 --out log.csv").status, 0);
  const std::string fit = "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --features auto ";
  for (const auto& [flag, method] : {std::pair<std::string, std::string>{"", "thermal_node"},
                                     {"--identify thermal-node ", "thermal_node"},
                                     {"--identify greedy ", "greedy"}}) {
    SCOPED_TRACE(flag);
    const auto result = run_thermodrift(dir, fit + flag + "--out model.json");
    ASSERT_EQ(result.status, 0) << result.err;
    const auto model = nlohmann::json::parse(read_file(dir.file("model.json")));
    EXPECT_EQ(model["axes"][0]["fit"]["feature_selection"]["method"], method);
  }
  for (const char* command : {"fit", "report", "demo"}) {
    const auto bad = run_thermodrift(dir, std::string(command) + " --identify bogus");
    EXPECT_EQ(bad.status, 2) << command;
    EXPECT_NE(bad.err.find("--identify"), std::string::npos) << bad.err;
  }
}

}  // namespace
}  // namespace thermodrift::testing
