// The typed fit record: every member survives the model file's JSON, files written before
// it was typed (with keys no version writes any more) still read, and a known key of the
// wrong type is an error that names it.
#include "thermodrift/models/fit_record.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

FitRecord every_member() {
  FitRecord r;
  r.terms = {"lag:600", "rate"};
  r.averaged_linear_part = true;
  r.partially_linear = true;
  r.stepwise_path = {{"add", "lag:600", 812.5}, {"drop", "rate", 1.25}};
  r.params = SvrParameters{12.5, 0.75, 1 / (2 * 0.75 * 0.75), 0.01};
  r.standardized = true;
  TuningRecord t;
  t.method = "afsa";
  t.objective = "cv";
  t.optimistic = false;
  t.folds = 5;
  t.folds_by = "runs";
  t.objective_mse = 0.0123;
  t.fits = 245;
  t.capped_fits = 3;
  t.seed = 18446744073709551615ull;  // the largest seed a user can give
  t.C_box = {0.01, 1000};
  t.sigma_box = {0.05, 20};
  t.epsilon_box = std::array<double, 2>{0.001, 0.2};
  t.epsilon = 0.01;
  t.history = {{7, 0.5}, {49, 0.0123}};
  r.tuning = t;
  SolverRecord s;
  s.termination = "converged";
  s.iterations = 4321;
  s.support_vectors = 321;
  s.dual_objective = -12.75;
  s.kernel = "nystrom";
  s.landmarks = 200;
  s.mean_kernel_residual = 1e-9;
  s.samples_outside_tube = 321;
  r.solver = s;
  r.evaluations = 49;
  CompressionRecord c;
  c.method = "kernel matching pursuit, least squares at the points";
  c.from_vectors = 321;
  c.to_vectors = 32;
  c.points = 321;
  c.rms_change = 0.002;
  c.max_change = 0.01;
  c.training_mse_before = 0.02;
  c.training_mse_after = 0.021;
  c.data_mse_before = 0.03;
  c.data_mse_after = 0.031;
  c.data = std::vector<std::string>{"cycle2.csv"};
  c.settle_seconds = 1800;
  r.compressed = c;
  KernelCheckRecord k;
  k.folds = 10;
  k.folds_by = "time";
  k.with_kernel_mse = 0.0125;
  k.linear_part_mse = 0.0121;
  k.min_gain = 0.1;
  k.kept = false;
  r.kernel_check = k;
  SelectionRecord f;
  f.method = "thermal_node";
  f.scored_by = "least squares";
  f.folds = 10;
  f.folds_by = "time";
  f.min_gain = 0.1;
  f.start_mse = 4.5;
  f.cv_mse = 0.02;
  f.candidates_scored = 2345;
  f.terms = r.terms;
  f.path = {{"node", "lag:600", 0.05, {"lag:600"}}, {"add", "rate", 0.02, {"lag:600", "rate"}}};
  f.temperature_channel = 2;
  f.power_on_start = true;
  f.node_under_dynamics = false;
  f.cv_score = "geometric_mean";
  r.feature_selection = f;
  r.training_samples = 2280;
  ResidualMetrics m;
  m.samples = 22800;
  m.mse_before = 3.5;
  m.mse_after = 0.02;
  m.residual_std = 0.14;
  m.residual_peak_to_peak = 0.9;
  r.in_sample = m;
  return r;
}

TEST(FitRecord, EveryMemberSurvivesItsJson) {
  const FitRecord record = every_member();
  const nlohmann::json json = fit_record_to_json(record);
  const FitRecord back = fit_record_from_json(json);
  EXPECT_EQ(fit_record_to_json(back), json);
  // Spot checks that the JSON holds the values, not only the same shape.
  ASSERT_TRUE(back.tuning && back.tuning->epsilon_box);
  EXPECT_EQ((*back.tuning->epsilon_box)[1], 0.2);
  EXPECT_EQ(back.tuning->seed, 18446744073709551615ull);
  EXPECT_EQ(back.tuning->history.back().evaluations, 49);
  ASSERT_TRUE(back.feature_selection);
  EXPECT_EQ(back.feature_selection->path.at(1).terms.at(1), "rate");
  EXPECT_EQ(back.feature_selection->temperature_channel, std::optional<std::size_t>(2));
  EXPECT_EQ(json["feature_selection"]["cv_score"], "geometric_mean");
  ASSERT_TRUE(back.compressed);
  EXPECT_EQ(back.compressed->data, std::optional<std::vector<std::string>>(std::vector<std::string>{"cycle2.csv"}));
  EXPECT_EQ(json["compressed"]["training_mse_unit"], "(deg/h)^2");
  EXPECT_EQ(json["tuning"]["box"]["epsilon"], nlohmann::json::array({0.001, 0.2}));
  ASSERT_TRUE(back.kernel_check);
  EXPECT_FALSE(back.kernel_check->kept);
  EXPECT_EQ(back.kernel_check->linear_part_mse, 0.0121);
}

TEST(FitRecord, AnEmptyRecordWritesOnlyItsTerms) {
  FitRecord record;
  record.terms = {"dT", "rate"};
  EXPECT_EQ(fit_record_to_json(record), (nlohmann::json{{"terms", {"dT", "rate"}}}));
  // A fixed ε (not tuned) is written as a number, and read back as one.
  TuningRecord tuning;
  tuning.epsilon = 0.05;
  record.tuning = tuning;
  const auto json = fit_record_to_json(record);
  EXPECT_EQ(json["tuning"]["box"]["epsilon"], 0.05);
  const FitRecord back = fit_record_from_json(json);
  EXPECT_FALSE(back.tuning->epsilon_box.has_value());
  EXPECT_EQ(back.tuning->epsilon, 0.05);
}

TEST(FitRecord, KeysNoVersionWritesAreIgnoredAndNullIsNotANumber) {
  const auto json = nlohmann::json::parse(R"({
    "terms": ["dT", "rate"], "grid_history": [[1, 2]], "method": "afsa", "note": "made by hand",
    "solver": {"termination": "converged", "dual_objective": null, "iterations": 12}
  })");
  const FitRecord record = fit_record_from_json(json);
  EXPECT_EQ(record.terms, (std::vector<std::string>{"dT", "rate"}));
  ASSERT_TRUE(record.solver);
  EXPECT_TRUE(std::isnan(record.solver->dual_objective));
  EXPECT_EQ(record.solver->iterations, 12);
  EXPECT_FALSE(fit_record_to_json(record).contains("grid_history"));
}

TEST(FitRecord, AKnownKeyOfTheWrongTypeIsAnErrorNamingIt) {
  const auto message = [](const char* text) {
    try {
      fit_record_from_json(nlohmann::json::parse(text));
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(R"({"tuning": {"folds": -3}})").find("fit.tuning.folds must be an integer"), std::string::npos)
      << message(R"({"tuning": {"folds": -3}})");
  EXPECT_NE(message(R"({"tuning": {"folds": 1e68}})").find("fit.tuning.folds"), std::string::npos);
  EXPECT_NE(message(R"({"params": {"C": "ten"}})").find("fit.params.C must be a number"), std::string::npos);
  EXPECT_NE(message(R"({"feature_selection": {"path": [{"terms": [1]}]}})").find("fit.feature_selection.path[0].terms"),
            std::string::npos);
  EXPECT_NE(message(R"({"tuning": {"box": {"C": [1]}}})").find("fit.tuning.box.C must be [low, high]"),
            std::string::npos);
  EXPECT_NE(message(R"([1, 2])").find("fit must be an object"), std::string::npos);
}

}  // namespace
}  // namespace thermodrift
