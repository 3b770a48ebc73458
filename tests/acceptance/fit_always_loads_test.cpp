// Every model file `fit` writes loads: over units drawn from the simulator's law family
// (development seeds) and every model, `fit --features auto` writes a file that
// `evaluate` reads and scores, and whose exported C header compiles as C99. A file the
// tool cannot load is a fit that failed silently. Minutes under the sanitizers: run in the
// Release pass (label acceptance) only.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift {
namespace {

using testing::CommandResult;
using testing::TempDir;

using testing::run_thermodrift;

using testing::kColumns;

// fit -> evaluate -> export -> compile; every step must succeed and every metric be finite.
void expect_round_trip(const TempDir& dir, const std::string& log, const std::string& model,
                       const std::string& fit_options) {
  SCOPED_TRACE(log + " " + model);
  const std::string file = log + "." + model + ".json";
  const auto fit = run_thermodrift(dir, "fit --data " + log + kColumns + " --model " + model + " --features auto" +
                                            fit_options + " --out " + file + " --json");
  ASSERT_EQ(fit.status, 0) << fit.err;
  // fit says what to expect held out: the blocked-CV MSE, against the floor estimate.
  const auto fitted = nlohmann::json::parse(fit.out);
  for (const auto& axis : fitted["axes"]) {
    ASSERT_TRUE(axis.contains("expected_held_out")) << axis.dump();
    EXPECT_GT(axis["expected_held_out"]["cv_mse"].get<double>(), 0.0);
    EXPECT_GT(axis["expected_held_out"]["x_floor_estimate"].get<double>(), 0.0);
  }
  const auto evaluate = run_thermodrift(dir, "evaluate --model " + file + " --data " + log + kColumns + " --json");
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  const auto result = nlohmann::json::parse(evaluate.out);
  ASSERT_EQ(result["axes"].size(), 3u);
  for (const auto& axis : result["axes"]) {
    const double after = axis["mse_after"].get<double>();
    EXPECT_TRUE(std::isfinite(after)) << axis.dump();
    EXPECT_LT(after, axis["mse_before"].get<double>()) << "in-sample, a fitted model must beat a constant";
  }
  const std::string header = log + "." + model + ".h";
  const auto exported = run_thermodrift(dir, "export --model " + file + " --out " + header);
  ASSERT_EQ(exported.status, 0) << exported.err;
  dir.write("use_" + model + ".c", "#include \"" + header + "\"\nint main(void) { return 0; }\n");
  const auto compiled = testing::run_in(dir, "gcc -std=c99 -Wall -Wextra -Werror -pedantic -c use_" + model +
                                                 ".c -o use_" + model + ".o");
  EXPECT_EQ(compiled.status, 0) << compiled.err;
}

// One test per law, so that ctest runs them side by side, and one model per law (each fit
// is a whole identification, about half a minute): law 2 linear, on the default search
// (the thermal node) and on the greedy one; law 8 stepwise, on a partial cycle; law 13
// linear with the node looked for on every thermometer (its x and z thermometers sit on
// each other's coils; z takes x's); law 5 (FitAlwaysLoadsSvr) the SVR, on a fast
// programme, as fit leaves it (its nested CV left the kernel out on every axis when this
// was written) and with the kernel kept, so that a file with support vectors goes through
// evaluate and export too.
class FitAlwaysLoads : public ::testing::TestWithParam<int> {};

TEST_P(FitAlwaysLoads, OneModelOnADrawnLaw) {
  TempDir dir;
  const int law = GetParam();
  const std::string log = "law" + std::to_string(law) + ".csv";
  const std::string profile = law == 8 ? "partial" : "cycle";
  const auto simulated = run_thermodrift(
      dir, "simulate --law " + std::to_string(law) + " --profile " + profile + " --cycles 1 --out " + log);
  ASSERT_EQ(simulated.status, 0) << simulated.err;
  if (law == 2) {
    expect_round_trip(dir, log, "linear", "");
    expect_round_trip(dir, log, "linear", " --identify greedy");
  }
  if (law == 8) expect_round_trip(dir, log, "stepwise", "");
  if (law == 13) {
    expect_round_trip(dir, log, "linear", " --node-channel any");
    const auto model = nlohmann::json::parse(testing::read_file(dir.file(log + ".linear.json")));
    EXPECT_EQ(model["axes"][2]["pipeline"].value("temperature_channel", 0), 1) << "z's node on x's thermometer";
  }
}

INSTANTIATE_TEST_SUITE_P(DevelopmentLaws, FitAlwaysLoads, ::testing::Values(2, 8, 13));

TEST(FitAlwaysLoadsSvr, SvrOnADrawnLaw) {
  TempDir dir;
  const auto simulated = run_thermodrift(dir, "simulate --law 5 --profile fast --cycles 1 --out law5.csv");
  ASSERT_EQ(simulated.status, 0) << simulated.err;
  expect_round_trip(dir, "law5.csv", "svr", " --evaluations 6");
  std::filesystem::copy_file(dir.file("law5.csv"), dir.file("kept.csv"));
  expect_round_trip(dir, "kept.csv", "svr", " --evaluations 6 --keep-kernel");
  const auto model = nlohmann::json::parse(testing::read_file(dir.file("kept.csv.svr.json")));
  for (const auto& axis : model["axes"]) {
    EXPECT_GT(axis["model"]["support_vectors"].size(), 0u) << "the kernel kept on every axis";
  }
}

}  // namespace
}  // namespace thermodrift
