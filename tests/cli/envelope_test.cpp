// How far to trust a model: fit records the training envelope and warns of what the log
// did not cover; evaluate and compensate count the samples outside it; both report the
// noise floor estimated from the log.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <memory>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"

namespace thermodrift {
namespace {

using testing::CommandResult;
using testing::read_file;
using testing::split_lines;
using testing::TempDir;
using testing::run_thermodrift;

using testing::kColumns;
// The default cycle heats from 20 to 60 °C after a one-hour soak, soaks an hour there,
// then cools: before this time the log has only heated.
constexpr double kHeatingEndsSeconds = 9600;

using testing::contains;

nlohmann::json parse(const CommandResult& result) {
  EXPECT_TRUE(nlohmann::json::accept(result.out)) << result.out;
  return nlohmann::json::accept(result.out) ? nlohmann::json::parse(result.out) : nlohmann::json::object();
}

// One default cycle (-40..60 °C), its heating-only start, and a cycle reaching 80 °C;
// a model fitted on the full cycle and one on its heating-only start.
class Envelope : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>();
    ASSERT_EQ(run_thermodrift(*dir_, "simulate --cycles 1 --out cycle.csv").status, 0);
    ASSERT_EQ(run_thermodrift(*dir_, "simulate --cycles 1 --seed 2 --max-temp 80 --out hot.csv").status, 0);
    const auto lines = split_lines(read_file(dir_->file("cycle.csv")));
    std::string heating = lines.front() + "\n";
    for (std::size_t i = 1; i < lines.size(); ++i) {
      if (std::stod(lines[i].substr(0, lines[i].find(','))) < kHeatingEndsSeconds) heating += lines[i] + "\n";
    }
    dir_->write("heating.csv", heating);
    full_fit_ = run_thermodrift(*dir_, "fit --data cycle.csv" + kColumns + " --out full.json --json");
    ASSERT_EQ(full_fit_.status, 0) << full_fit_.err;
    heating_fit_ = run_thermodrift(*dir_, "fit --data heating.csv" + kColumns + " --out heating.json --json");
    ASSERT_EQ(heating_fit_.status, 0) << heating_fit_.err;
  }
  static void TearDownTestSuite() { dir_.reset(); }

  static std::unique_ptr<TempDir> dir_;
  static CommandResult full_fit_, heating_fit_;
};

std::unique_ptr<TempDir> Envelope::dir_;
CommandResult Envelope::full_fit_, Envelope::heating_fit_;

TEST_F(Envelope, FitRecordsTheEnvelopeAndTheFloorEstimate) {
  EXPECT_FALSE(contains(full_fit_.err, "never seen")) << full_fit_.err;
  const auto json = parse(full_fit_);
  ASSERT_EQ(json["axes"].size(), 3u);
  for (const auto& axis : json["axes"]) {
    const auto& envelope = axis.at("training_envelope");
    EXPECT_TRUE(envelope.at("heating_seen").get<bool>());
    EXPECT_TRUE(envelope.at("cooling_seen").get<bool>());
    EXPECT_LT(envelope["temperature_c"][0].get<double>(), -30.0);  // the housing lags the chamber's -40
    EXPECT_GT(envelope["temperature_c"][1].get<double>(), 50.0);
    EXPECT_EQ(envelope.at("terms").size(), 2u);
    // The simulator's floor at 100 s is about 4.3e-4 (°/h)².
    EXPECT_NEAR(axis.at("noise_floor_estimate").get<double>(), 4.3e-4, 1.5e-4);
    EXPECT_NEAR(axis.at("mse_after_x_floor").get<double>(),
                axis["mse_after"].get<double>() / axis["noise_floor_estimate"].get<double>(), 1e-9);
  }
  // The model file holds the same envelope.
  const auto model = nlohmann::json::parse(read_file(dir_->file("full.json")));
  EXPECT_EQ(model["axes"][0]["training_envelope"], json["axes"][0]["training_envelope"]);
}

TEST_F(Envelope, FitOnAHeatingOnlyLogWarnsAboutCooling) {
  EXPECT_TRUE(contains(heating_fit_.err, "gyro_x: the model has never seen cooling")) << heating_fit_.err;
  EXPECT_FALSE(contains(heating_fit_.err, "never seen heating")) << heating_fit_.err;
  const auto json = parse(heating_fit_);  // the warning stays off stdout
  EXPECT_FALSE(json["axes"][0]["training_envelope"]["cooling_seen"].get<bool>());
  const auto table = run_thermodrift(*dir_, "fit --data heating.csv" + kColumns + " --out table.json");
  ASSERT_EQ(table.status, 0) << table.err;
  EXPECT_TRUE(contains(table.out, "gyro_x training envelope: T ")) << table.out;
  EXPECT_TRUE(contains(table.out, "heating seen, cooling never")) << table.out;
  EXPECT_TRUE(contains(table.out, "noise floor (estimate")) << table.out;
}

TEST_F(Envelope, EvaluateFlagsTheCoolingAHeatingOnlyModelNeverSaw) {
  const auto result = run_thermodrift(*dir_, "evaluate --model heating.json --data cycle.csv --json");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_TRUE(contains(result.err, "outside the training envelope")) << result.err;
  EXPECT_TRUE(contains(result.err, "cooling never seen in training")) << result.err;
  const nlohmann::json evaluated = parse(result);  // kept alive: the loop walks inside it
  for (const auto& axis : evaluated["axes"]) {
    const auto outside = axis.at("outside_envelope").get<std::size_t>();
    EXPECT_GT(outside, 0u);
    EXPECT_GT(axis["outside_envelope_by_limit"]["direction"].get<std::size_t>(), 0u);
    EXPECT_NEAR(axis.at("outside_envelope_fraction").get<double>(),
                static_cast<double>(outside) / axis["samples"].get<double>(), 1e-12);
    EXPECT_TRUE(axis.contains("mse_after_x_floor"));
  }
}

TEST_F(Envelope, EvaluateCountsAHotterLogOutsideAndItsOwnLogInside) {
  const auto own = run_thermodrift(*dir_, "evaluate --model full.json --data cycle.csv --json");
  ASSERT_EQ(own.status, 0) << own.err;
  EXPECT_FALSE(contains(own.err, "envelope")) << own.err;
  const nlohmann::json own_json = parse(own);
  for (const auto& axis : own_json["axes"]) EXPECT_EQ(axis.at("outside_envelope").get<std::size_t>(), 0u);

  const auto hot = run_thermodrift(*dir_, "evaluate --model full.json --data hot.csv --json");
  ASSERT_EQ(hot.status, 0) << hot.err;
  EXPECT_TRUE(contains(hot.err, "temperature above")) << hot.err;
  const nlohmann::json hot_json = parse(hot);
  for (const auto& axis : hot_json["axes"]) {
    EXPECT_GT(axis["outside_envelope_by_limit"]["temperature"].get<std::size_t>(), 0u) << axis.dump();
    EXPECT_GT(axis.at("outside_envelope_fraction").get<double>(), 0.0);
    EXPECT_LT(axis.at("outside_envelope_fraction").get<double>(), 0.5);
  }
  const auto table = run_thermodrift(*dir_, "evaluate --model full.json --data hot.csv");
  EXPECT_TRUE(contains(table.out, "gyro_x outside the training envelope: ")) << table.out;
}

TEST_F(Envelope, CompensateWarnsOfAHotterLogAndFlagsItsRows) {
  const auto result = run_thermodrift(*dir_, "compensate --model full.json --data hot.csv --flags --out flagged.csv");
  ASSERT_EQ(result.status, 0) << result.err;
  const std::regex warning(
      R"(compensate: gyro_x: (\d+) of (\d+) rows outside the training envelope \(temperature above [0-9.]+ °C[^)]*\); (\d+) rows not ready \(warm-up\))");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(result.err, match, warning)) << result.err;
  const auto lines = split_lines(read_file(dir_->file("flagged.csv")));
  ASSERT_GT(lines.size(), 2u);
  EXPECT_TRUE(lines[0].ends_with(",gyro_x_comp_dph,gyro_y_comp_dph,gyro_z_comp_dph,gyro_x_flags,gyro_y_flags,gyro_z_flags"))
      << lines[0];
  std::size_t outside = 0, not_ready = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    // gyro_x_flags is the third column from the end.
    std::vector<std::string> cells;
    std::stringstream row(lines[i]);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    const int flags = std::stoi(cells[cells.size() - 3]);
    ASSERT_TRUE(flags == 0 || flags == 1 || flags == 2) << "line " << i + 1 << ": " << lines[i];
    outside += (flags & 2) != 0;
    not_ready += (flags & 1) != 0;
  }
  EXPECT_EQ(std::to_string(outside), match[1].str());
  EXPECT_EQ(std::to_string(lines.size() - 1), match[2].str());
  EXPECT_EQ(std::to_string(not_ready), match[3].str());
  EXPECT_TRUE(lines[1].ends_with(",1,1,1")) << lines[1];  // the first row is in the warm-up

  // Without --flags the output keeps its columns.
  const auto plain = run_thermodrift(*dir_, "compensate --model full.json --data hot.csv --out plain.csv");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_TRUE(split_lines(read_file(dir_->file("plain.csv")))[0].ends_with("gyro_z_comp_dph"));
}

// A log inside the envelope compensates without a word (its warm-up is normal); a log
// shorter than the warm-up is never ready, and that is said per axis.
TEST_F(Envelope, CompensateIsQuietInsideTheEnvelopeAndSaysWhenNeverReady) {
  const auto own = run_thermodrift(*dir_, "compensate --model full.json --data cycle.csv --out own.csv");
  ASSERT_EQ(own.status, 0) << own.err;
  EXPECT_FALSE(contains(own.err, "compensate: ")) << own.err;

  const auto lines = split_lines(read_file(dir_->file("cycle.csv")));
  std::string head;
  for (std::size_t i = 0; i < 51 && i < lines.size(); ++i) head += lines[i] + "\n";
  dir_->write("short.csv", head);
  const auto short_log = run_thermodrift(*dir_, "compensate --model full.json --data short.csv --out short_out.csv");
  ASSERT_EQ(short_log.status, 0) << short_log.err;
  EXPECT_TRUE(contains(short_log.err, "gyro_x: never ready: all 50 rows")) << short_log.err;
}

// The paper's pair on the default unit leaves hundreds of times the floor: fit says so, with
// the figure it prints (in-sample without CV, the expected held-out MSE with it).
TEST_F(Envelope, FitWarnsWhenTheModelIsFarFromTheFloor) {
  const auto json = parse(full_fit_);
  for (const auto& axis : json["axes"]) {
    const auto name = axis.at("name").get<std::string>();
    ASSERT_FALSE(axis.contains("expected_held_out")) << axis.dump();  // fixed C and σ: no CV
    ASSERT_GT(axis.at("mse_after_x_floor").get<double>(), 2.0);
    const std::regex line(name + R"(: on its training data it leaves ([0-9.e+]+) × the noise floor estimate: the model )"
                                 R"(does not describe this unit's drift down to the noise)");
    std::smatch match;
    ASSERT_TRUE(std::regex_search(full_fit_.err, match, line)) << full_fit_.err;
    EXPECT_TRUE(contains(full_fit_.err, "; --features auto, or another chamber programme")) << full_fit_.err;
    EXPECT_NEAR(std::stod(match[1].str()), axis["mse_after_x_floor"].get<double>(),
                1e-2 * axis["mse_after_x_floor"].get<double>());
  }
  const auto tuned = run_thermodrift(*dir_, "fit --data cycle.csv --gyro gyro_x --temp temp_x --model svr "
                                            "--evaluations 9 --out tuned.json --json");
  ASSERT_EQ(tuned.status, 0) << tuned.err;
  const double held_out = parse(tuned)["axes"][0]["expected_held_out"]["x_floor_estimate"].get<double>();
  ASSERT_GT(held_out, 2.0);
  EXPECT_TRUE(contains(tuned.err, "gyro_x: its expected held-out MSE is ")) << tuned.err;
  // --json lists the warnings stderr gave, for a script that reads stdout only.
  const auto warnings = parse(tuned).at("warnings");
  ASSERT_TRUE(warnings.is_array());
  ASSERT_FALSE(warnings.empty());
  for (const auto& warning : warnings) {
    EXPECT_TRUE(contains(tuned.err, "thermodrift: warning: " + warning.get<std::string>())) << warning;
  }
  EXPECT_TRUE(contains(warnings.back().get<std::string>(), "gyro_x: its expected held-out MSE is ")) << warnings;
}

// A drift the model holds exactly (linear in the temperature, white noise): no warning.
TEST(FarFromTheFloor, FitIsQuietWhenTheModelReachesTheFloor) {
  TempDir dir;
  std::mt19937_64 generator(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::string csv = "time_s,temp,gyro\n";
  for (int t = 0; t < 6 * 3600; ++t) {
    const double temp = 20.0 + 20.0 * std::sin(2 * M_PI * t / 10800.0);
    csv += std::to_string(t) + "," + std::to_string(temp) + "," + std::to_string(0.05 * temp + noise(generator)) + "\n";
  }
  dir.write("line.csv", csv);
  const auto fit = run_thermodrift(dir, "fit --data line.csv --gyro gyro --temp temp --model linear --features dT "
                                        "--out line.json --json");
  ASSERT_EQ(fit.status, 0) << fit.err;
  const double ratio = parse(fit)["axes"][0].at("mse_after_x_floor").get<double>();
  EXPECT_LT(ratio, 1.5);
  EXPECT_FALSE(contains(fit.err, "noise floor estimate")) << fit.err;
  EXPECT_EQ(parse(fit).at("warnings"), nlohmann::json::array());
}

}  // namespace
}  // namespace thermodrift
