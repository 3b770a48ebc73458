// thermodrift compress and fit --max-vectors: a smaller SVR written as an ordinary model
// file that the other commands take, with figures that describe the file written.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "../support/fitted_model.hpp"
#include "../support/temp_dir.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::testing {
namespace {

const std::string kTwoAxes = " --gyro gyro_x,gyro_y --temp temp_x,temp_y";

std::size_t most_vectors(const std::string& model_file) {
  std::size_t most = 0;
  const auto model = nlohmann::json::parse(read_file(model_file));
  for (const auto& axis : model["axes"]) {
    most = std::max(most, axis["model"]["coefficients"].size());
  }
  return most;
}

double mse_after(const TempDir& dir, const std::string& model_file, std::size_t axis) {
  const auto result = run_thermodrift(dir, "evaluate --json --model " + model_file + " --data log.csv" + kTwoAxes);
  EXPECT_EQ(result.status, 0) << result.err;
  return nlohmann::json::parse(result.out)["axes"][axis]["mse_after"].get<double>();
}

TEST(Compress, WritesAModelOfAtMostKVectorsThatPredictsLikeTheOriginal) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  const auto fit = run_thermodrift(dir, "fit --data log.csv --model svr --C 100 --sigma 1 --out svr.json" + kTwoAxes);
  ASSERT_EQ(fit.status, 0) << fit.err;
  ASSERT_GT(most_vectors(dir.file("svr.json")), 100u);

  const auto compressed = run_thermodrift(
      dir, "compress --model svr.json --max-vectors 24 --data log.csv --json --out small.json" + kTwoAxes);
  ASSERT_EQ(compressed.status, 0) << compressed.err;
  EXPECT_LE(most_vectors(dir.file("small.json")), 24u);
  const auto report = nlohmann::json::parse(compressed.out);
  ASSERT_EQ(report["axes"].size(), 2u);
  for (std::size_t a = 0; a < 2; ++a) {
    SCOPED_TRACE(a);
    const auto& record = report["axes"][a]["compressed"];
    // The figures printed are those of the files: evaluate finds the same MSE before and after.
    EXPECT_NEAR(record["data_mse_before"].get<double>(), mse_after(dir, "svr.json", a), 1e-12);
    EXPECT_NEAR(record["data_mse_after"].get<double>(), mse_after(dir, "small.json", a), 1e-12);
    EXPECT_LT(record["data_mse_after"].get<double>(), 1.05 * record["data_mse_before"].get<double>());
    EXPECT_GT(record["from_vectors"].get<std::size_t>(), record["to_vectors"].get<std::size_t>());
  }
  // An ordinary model: compensate and export take it.
  EXPECT_EQ(run_thermodrift(dir, "compensate --model small.json --data log.csv --out c.csv").status, 0);
  EXPECT_EQ(run_thermodrift(dir, "export --model small.json --out small.h").status, 0);
}

TEST(Compress, FitMaxVectorsRecordsTheInSampleCost) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.2 --out log.csv").status, 0);
  const auto fit = run_thermodrift(
      dir, "fit --data log.csv --model svr --C 100 --sigma 1 --max-vectors 32 --json --out svr.json" + kTwoAxes);
  ASSERT_EQ(fit.status, 0) << fit.err;
  EXPECT_LE(most_vectors(dir.file("svr.json")), 32u);
  const auto printed = nlohmann::json::parse(fit.out);
  for (const auto& axis : printed["axes"]) {
    const auto& record = axis["compressed"];
    EXPECT_GT(record["training_mse_before"].get<double>(), 0);
    EXPECT_LT(record["training_mse_after"].get<double>(), 1.05 * record["training_mse_before"].get<double>());
  }
}

// An SVR axis without support vectors (its kernel left out by fit's nested CV, or none
// trained) has nothing to reduce: compress says so per axis, and still writes a model
// the other commands take.
TEST(Compress, SaysPerAxisWhenAnAxisHasNothingToReduce) {
  TempDir dir;
  sim::SimulatorOptions options;
  options.cycles = 1;
  options.rate_hz = 0.1;
  const ChamberLog log = sim::to_chamber_log(sim::simulate(options));
  DriftModel model = fitted_model(log, {.kind = "linear_part_only", .terms = {"lag:420", "lagrate:420", "rate"}});
  model.axes[0].fit.kernel_check = KernelCheckRecord{.folds = 10, .with_kernel_mse = 2, .linear_part_mse = 1,
                                                     .min_gain = 0.1, .kept = false};
  save_drift_model(model, dir.file("none.json"), {});

  const auto text = run_thermodrift(dir, "compress --model none.json --out small.json");
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_TRUE(contains(text.out, "gyro_x: 0 support vectors, nothing to reduce (the kernel was left out: the axis is "
                                 "its linear part)\n"))
      << text.out;
  EXPECT_TRUE(contains(text.out, "gyro_y: 0 support vectors, nothing to reduce\n")) << text.out;
  EXPECT_TRUE(std::filesystem::exists(dir.file("small.json")));

  const auto json = run_thermodrift(dir, "compress --model none.json --json --out small2.json");
  ASSERT_EQ(json.status, 0) << json.err;
  const auto printed = nlohmann::json::parse(json.out);
  ASSERT_EQ(printed["axes"].size(), log.axes());
  for (std::size_t a = 0; a < log.axes(); ++a) {
    EXPECT_EQ(printed["axes"][a]["name"], log.gyro_names[a]);
    EXPECT_TRUE(printed["axes"][a].contains("unchanged")) << printed["axes"][a];
    EXPECT_FALSE(printed["axes"][a].contains("compressed")) << printed["axes"][a];
  }
}

TEST(Compress, RefusesWhatItCannotCompress) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --model linear --out linear.json" + kTwoAxes).status, 0);
  const auto linear = run_thermodrift(dir, "compress --model linear.json --out small.json");
  EXPECT_EQ(linear.status, 2);
  EXPECT_NE(linear.err.find("has no SVR axis"), std::string::npos) << linear.err;
  const auto option = run_thermodrift(dir, "fit --data log.csv --model linear --max-vectors 8 --out m.json" + kTwoAxes);
  EXPECT_EQ(option.status, 2);
  EXPECT_NE(option.err.find("--max-vectors applies to --model svr"), std::string::npos) << option.err;
  EXPECT_EQ(run_thermodrift(dir, "compress --model linear.json --max-vectors 0 --out small.json").status, 2);
  EXPECT_FALSE(std::filesystem::exists(dir.file("small.json")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
}

}  // namespace
}  // namespace thermodrift::testing
