// Several --data files are separate runs: with --folds-by runs, fit's cross-validation
// holds out whole runs (leave-one-run-out); evaluate reports each run and all together.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

class Runs : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(run_thermodrift(dir_, "simulate --cycles 1 --rate 0.1 --min-temp 10 --max-temp 35 --soak 20 --seed 5 --out a.csv").status, 0);
    ASSERT_EQ(run_thermodrift(dir_, "simulate --cycles 1 --rate 0.1 --min-temp 10 --max-temp 35 --soak 20 --seed 6 --ramp 2 --out b.csv").status, 0);
  }
  nlohmann::json fit(const std::string& options) {
    const auto result = run_thermodrift(dir_, "fit --data a.csv --data b.csv --gyro gyro_x --temp temp_x " +
                                                  options + " --out model.json --json");
    EXPECT_EQ(result.status, 0) << result.err;
    return nlohmann::json::parse(read_file(dir_.file("model.json")));
  }
  TempDir dir_;
};

TEST_F(Runs, FeatureSearchHoldsOutWholeRunsWhenAsked) {
  const auto by_runs = fit("--model linear --features auto --folds-by runs");
  const auto& selection = by_runs["axes"][0]["fit"]["feature_selection"];
  EXPECT_EQ(selection["folds_by"], "runs");
  EXPECT_EQ(selection["folds"], 2);
  // The default, blocks in time, on the greedy search (a tenth of the thermal node's cost
  // under the sanitizers; the two share the CV blocks).
  const auto by_time = fit("--model linear --features auto --identify greedy");
  EXPECT_EQ(by_time["axes"][0]["fit"]["feature_selection"]["folds_by"], "time");
  EXPECT_EQ(by_time["axes"][0]["fit"]["feature_selection"]["folds"], 10);
  // One run falls back to blocks in time whatever --folds-by says: CvBlocks' unit test.
  const auto bad = run_thermodrift(dir_, "fit --data a.csv --folds-by shuffled --out x.json");
  EXPECT_EQ(bad.status, 2);
}

TEST_F(Runs, SvrTuningHoldsOutWholeRunsAndSaysSo) {
  const auto model = fit("--model svr --evaluations 4 --folds-by runs");
  const auto& tuning = model["axes"][0]["fit"]["tuning"];
  EXPECT_EQ(tuning["folds_by"], "runs");
  EXPECT_EQ(tuning["folds"], 2);
  const auto result = run_thermodrift(dir_, "fit --data a.csv --data b.csv --gyro gyro_x --temp temp_x --model svr "
                                            "--evaluations 4 --folds-by runs --out m.json");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_NE(result.out.find("leave-one-run-out (2 runs)"), std::string::npos) << result.out;
}

TEST_F(Runs, EvaluateReportsEachRunAndAllTogether) {
  fit("--model linear");
  const auto result = run_thermodrift(dir_, "evaluate --model model.json --data a.csv --data b.csv --json");
  ASSERT_EQ(result.status, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  ASSERT_EQ(json["runs"].size(), 2u);
  EXPECT_NE(json["runs"][0]["file"].get<std::string>().find("a.csv"), std::string::npos);
  {  // the pooled MSE is the sample-weighted mean of the runs' MSEs
    double samples = 0, weighted = 0;
    for (const auto& run : json["runs"]) {
      const auto& entry = run["axes"][0];
      samples += entry["samples"].get<double>();
      weighted += entry["samples"].get<double>() * entry["mse_after"].get<double>();
    }
    const auto& all = json["axes"][0];
    EXPECT_EQ(samples, all["samples"].get<double>());
    EXPECT_NEAR(weighted / samples, all["mse_after"].get<double>(), 1e-9 * all["mse_after"].get<double>());
  }
  const auto one = run_thermodrift(dir_, "evaluate --model model.json --data a.csv --json");
  ASSERT_EQ(one.status, 0) << one.err;
  EXPECT_FALSE(nlohmann::json::parse(one.out).contains("runs"));
}

}  // namespace
}  // namespace thermodrift::testing
