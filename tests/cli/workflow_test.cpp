// The command line end to end (simulate -> fit on cycle 1 -> evaluate and compensate on
// cycle 2) and its error contract: one line on stderr naming file:line:column, exit 2 for
// usage, 3 for bad data, and no output file or temporary left behind by a failure.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../support/one_line_error.hpp"
#include "../support/temp_dir.hpp"

namespace thermodrift {
namespace {

using testing::CommandResult;
using testing::read_file;
using testing::split_lines;
using testing::TempDir;

using testing::kBinary;
constexpr double kCycleSeconds = 22800;  // one default chamber cycle
using testing::kTemps;

using testing::run_thermodrift;

using testing::contains;

using testing::expect_one_line;

// The simulated two-cycle run and its split into cycles, made once for every test here.
class Workflow : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    shared_ = std::make_unique<TempDir>();
    const auto result = run_thermodrift(*shared_, "simulate --cycles 2 --out sim.csv");
    ASSERT_EQ(result.status, 0) << result.err;
    const auto lines = split_lines(read_file(shared_->file("sim.csv")));
    ASSERT_GT(lines.size(), 2 * kCycleSeconds);
    header_ = lines.front();
    std::string first = header_ + "\n", second = header_ + "\n";
    for (std::size_t i = 1; i < lines.size(); ++i) {
      const double time = std::stod(lines[i].substr(0, lines[i].find(',')));
      (time < kCycleSeconds ? first : second) += lines[i] + "\n";
    }
    cycle1_ = shared_->write("cycle1.csv", first);
    cycle2_ = shared_->write("cycle2.csv", second);
    const auto fit =
        run_thermodrift(*shared_, "fit --data cycle1.csv" + kTemps + " --model linear --out model.json --json");
    ASSERT_EQ(fit.status, 0) << fit.err;
    fit_stdout_ = fit.out;
    model_ = shared_->file("model.json");
  }
  static void TearDownTestSuite() { shared_.reset(); }

  // Copies a shared file into this test's own directory.
  std::string copy(const std::string& from, const std::string& name) { return dir_.write(name, read_file(from)); }

  static std::unique_ptr<TempDir> shared_;
  static std::string header_, cycle1_, cycle2_, model_, fit_stdout_;
  TempDir dir_;
};

std::unique_ptr<TempDir> Workflow::shared_;
std::string Workflow::header_, Workflow::cycle1_, Workflow::cycle2_, Workflow::model_, Workflow::fit_stdout_;

TEST_F(Workflow, SimulatedCsvHasTheDocumentedColumnsAndSplitsIntoTwoCycles) {
  EXPECT_TRUE(header_.starts_with("time_s,temp_chamber,temp_x,temp_y,temp_z,gyro_x,gyro_y,gyro_z,drift_x"))
      << header_;
  const auto first = split_lines(read_file(cycle1_));
  const auto second = split_lines(read_file(cycle2_));
  EXPECT_EQ(first.size(), 1 + static_cast<std::size_t>(kCycleSeconds));  // 1 Hz
  EXPECT_GE(second.size(), static_cast<std::size_t>(kCycleSeconds));
}

TEST_F(Workflow, FitJsonIsOneObjectWithThreeAxes) {
  const auto json = nlohmann::json::parse(fit_stdout_);  // throws on anything but one JSON document
  ASSERT_TRUE(json.is_object());
  ASSERT_EQ(json.at("axes").size(), 3u);
  const std::vector<std::string> names = {"gyro_x", "gyro_y", "gyro_z"};
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& axis = json["axes"][a];
    EXPECT_EQ(axis.at("name"), names[a]);
    EXPECT_EQ(axis.at("model"), "linear");
    EXPECT_TRUE(axis.contains("params"));
    EXPECT_TRUE(axis.contains("evaluations"));
    EXPECT_TRUE(axis.contains("seconds"));
    EXPECT_EQ(axis.at("terms"), nlohmann::json::array({"dT", "rate"}));  // the paper's pair by default
    EXPECT_FALSE(axis.contains("feature_selection"));
    EXPECT_LT(axis.at("mse_after").get<double>(), axis.at("mse_before").get<double>());
  }
}

TEST_F(Workflow, EvaluateOnTheSecondCycleBeatsNoModel) {
  const auto result = run_thermodrift(*shared_, "evaluate --model model.json --data cycle2.csv --json");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_EQ(result.err, "");
  nlohmann::json json;
  ASSERT_NO_THROW(json = nlohmann::json::parse(result.out)) << result.out;  // nothing but the JSON
  ASSERT_TRUE(json.is_object());
  ASSERT_TRUE(json.at("axes").is_array());
  ASSERT_EQ(json["axes"].size(), 3u);
  for (const auto& axis : json["axes"]) {
    ASSERT_TRUE(axis.contains("name"));
    const double before = axis.at("mse_before").get<double>();
    const double after = axis.at("mse_after").get<double>();
    EXPECT_TRUE(std::isfinite(before) && std::isfinite(after));
    EXPECT_GT(after, 0.0);
    EXPECT_LT(after, before) << axis.dump();
  }
}

TEST_F(Workflow, EvaluateWithoutJsonPrintsATable) {
  const auto result = run_thermodrift(*shared_, "evaluate --model model.json --data cycle2.csv");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_TRUE(contains(result.out, "gyro_x")) << result.out;
  EXPECT_FALSE(nlohmann::json::accept(result.out));  // a table, not JSON
}

TEST_F(Workflow, CompensateWritesEveryRowPlusOneColumnPerAxis) {
  const auto input = copy(cycle2_, "in.csv");
  const auto model = copy(model_, "model.json");
  const auto result = run_thermodrift(dir_, "compensate --model model.json --data in.csv --out out.csv");
  ASSERT_EQ(result.status, 0) << result.err;
  const auto in_lines = split_lines(read_file(input));
  const auto out_lines = split_lines(read_file(dir_.file("out.csv")));
  ASSERT_EQ(out_lines.size(), in_lines.size());
  EXPECT_EQ(out_lines[0], in_lines[0] + ",gyro_x_comp_dph,gyro_y_comp_dph,gyro_z_comp_dph");
  const auto columns = static_cast<std::size_t>(std::count(in_lines[0].begin(), in_lines[0].end(), ',')) + 1;
  // gyro_x is column 6, its compensation column `columns + 1`: the compensated rate
  // varies far less than the raw rate once warmed up.
  double raw_sum = 0, raw_sq = 0, comp_sum = 0, comp_sq = 0;
  std::size_t n = 0;
  for (std::size_t i = 1; i < in_lines.size(); ++i) {
    ASSERT_TRUE(out_lines[i].starts_with(in_lines[i] + ",")) << "line " << i + 1;
    std::vector<std::string> cells;
    std::stringstream row(out_lines[i]);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), columns + 3) << "line " << i + 1;
    if (i < 1000) continue;
    const double raw = std::stod(cells[5]);
    const double comp = std::stod(cells[columns]);
    ASSERT_TRUE(std::isfinite(comp));
    raw_sum += raw, raw_sq += raw * raw, comp_sum += comp, comp_sq += comp * comp, ++n;
  }
  const double raw_var = raw_sq / n - (raw_sum / n) * (raw_sum / n);
  const double comp_var = comp_sq / n - (comp_sum / n) * (comp_sum / n);
  EXPECT_LT(comp_var, 0.5 * raw_var) << comp_var << " vs " << raw_var;
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"in.csv", "model.json", "out.csv"}));
}

// --- the error contract ---

const std::string kSmallHeader = "time_s,temp,gyro_x\n";

std::string small_log(std::size_t rows) {
  std::string text = kSmallHeader;
  for (std::size_t i = 0; i < rows; ++i) text += std::to_string(i) + ",20,1\n";
  return text;
}

const std::string kSmallColumns = " --gyro gyro_x --temp temp --smooth 1";

TEST(CliErrors, BadCellIsExit3NamingFileLineAndColumn) {
  TempDir dir;
  std::string text = small_log(50);
  text.replace(text.find("\n3,20,1\n") + 1, 6, "3,20,1x");  // line 5, column 3
  dir.write("bad.csv", text);
  const auto result = run_thermodrift(dir, "fit --data bad.csv" + kSmallColumns + " --out model.json");
  EXPECT_EQ(result.status, 3) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "bad.csv:5:3: '1x' is not a number")) << result.err;
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"bad.csv"});  // no model, no temporary
}

TEST(CliErrors, TimeBackwardsIsExit3NamingFileLineAndColumn) {
  TempDir dir;
  std::string text = small_log(50);
  text.replace(text.find("\n7,20,1\n") + 1, 1, "2");  // line 9 says t = 2 after t = 6
  dir.write("back.csv", text);
  const auto result = run_thermodrift(dir, "fit --data back.csv" + kSmallColumns + " --out model.json");
  EXPECT_EQ(result.status, 3) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "back.csv:9:1: time goes backwards")) << result.err;
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"back.csv"});
}

TEST(CliErrors, TimeRepeatedNaNAndMissingColumnAreExit3) {
  TempDir dir;
  std::string repeated = small_log(30);
  repeated.replace(repeated.find("\n5,20,1\n") + 1, 1, "4");
  dir.write("repeat.csv", repeated);
  auto result = run_thermodrift(dir, "fit --data repeat.csv" + kSmallColumns + " --out m.json");
  EXPECT_EQ(result.status, 3);
  EXPECT_TRUE(contains(result.err, "repeat.csv:7:1: ")) << result.err;
  expect_one_line(result);

  std::string nan = small_log(30);
  nan.replace(nan.find("\n5,20,1\n") + 1, 6, "5,nan,1");
  dir.write("nan.csv", nan);
  result = run_thermodrift(dir, "fit --data nan.csv" + kSmallColumns + " --out m.json");
  EXPECT_EQ(result.status, 3);
  EXPECT_TRUE(contains(result.err, "nan.csv:7:2: 'nan' is not a finite number")) << result.err;
  expect_one_line(result);

  dir.write("ok.csv", small_log(30));
  result = run_thermodrift(dir, "fit --data ok.csv --gyro gyro_q --temp temp --out m.json");
  EXPECT_EQ(result.status, 3);
  EXPECT_TRUE(contains(result.err, "ok.csv:1: no gyro column named 'gyro_q'")) << result.err;
  expect_one_line(result);
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
}

TEST(CliErrors, EmptyFileAndOnlyHeaderAreExit3) {
  TempDir dir;
  dir.write("empty.csv", "");
  dir.write("header.csv", kSmallHeader);
  auto result = run_thermodrift(dir, "fit --data empty.csv" + kSmallColumns + " --out m.json");
  EXPECT_EQ(result.status, 3);
  expect_one_line(result);
  result = run_thermodrift(dir, "fit --data header.csv" + kSmallColumns + " --out m.json");
  EXPECT_EQ(result.status, 3);
  EXPECT_TRUE(contains(result.err, "header.csv:1: only a header")) << result.err;
  expect_one_line(result);
}

TEST(CliErrors, FewerRowsThanTheWarmUpIsExit3) {
  TempDir dir;
  dir.write("short.csv", small_log(50));  // 50 s of data, 100 s smoothing
  for (const std::string features : {"", " --model svr --features auto"}) {
    const auto result = run_thermodrift(dir, "fit --data short.csv --gyro gyro_x --temp temp --out m.json" + features);
    EXPECT_EQ(result.status, 3) << features << ": " << result.err;
    expect_one_line(result);
    EXPECT_TRUE(contains(result.err, "short.csv: too little data after the 200 s warm-up")) << result.err;
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"short.csv"});
  }
}

TEST(CliErrors, ConstantTemperatureFitsWithFiniteNumbers) {
  // ΔT is collinear with the intercept: a documented rank deficiency, never NaN or a
  // pair of huge cancelling coefficients.
  TempDir dir;
  std::string text = kSmallHeader;
  for (int i = 0; i < 400; ++i) text += std::to_string(i) + ",20," + std::to_string(1 + (i % 5) * 0.01) + "\n";
  dir.write("flat.csv", text);
  const auto fit = run_thermodrift(dir, "fit --data flat.csv" + kSmallColumns + " --model linear --out m.json --json");
  ASSERT_EQ(fit.status, 0) << fit.err;
  const auto model = nlohmann::json::parse(read_file(dir.file("m.json")));
  const auto& linear = model.at("axes").at(0).at("model");
  EXPECT_EQ(linear.at("rank_deficiency"), 2);  // dT is constant and dT/dt is 0
  EXPECT_TRUE(linear.at("intercept").is_number());
  for (const auto& c : linear.at("coefficients")) {
    ASSERT_TRUE(c.is_number()) << linear.dump();
    EXPECT_LT(std::abs(c.get<double>()), 10.0) << linear.dump();
  }
  EXPECT_LT(std::abs(linear.at("intercept").get<double>()), 10.0) << linear.dump();
  const auto evaluate = run_thermodrift(dir, "evaluate --model m.json --data flat.csv --json");
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  const auto json = nlohmann::json::parse(evaluate.out);
  EXPECT_TRUE(json.at("axes").at(0).at("mse_after").is_number()) << evaluate.out;  // NaN would be null
}

TEST(CliErrors, UnknownOptionIsExit2) {
  TempDir dir;
  dir.write("ok.csv", small_log(30));
  const auto result = run_thermodrift(dir, "fit --data ok.csv" + kSmallColumns + " --out m.json --bogus 3");
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "--bogus")) << result.err;
  EXPECT_EQ(result.out, "");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"ok.csv"});
}

TEST(CliErrors, MissingRequiredOptionIsExit2) {
  TempDir dir;
  dir.write("ok.csv", small_log(30));
  auto result = run_thermodrift(dir, "fit --data ok.csv" + kSmallColumns);  // no --out
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "--out")) << result.err;

  result = run_thermodrift(dir, "evaluate --data ok.csv");  // no --model
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);

  result = run_thermodrift(dir, "simulate");  // no --out
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);

  result = run_thermodrift(dir, "");  // no subcommand
  EXPECT_EQ(result.status, 2) << result.err;
}

TEST(CliErrors, BadOptionValueIsExit2) {
  TempDir dir;
  dir.write("ok.csv", small_log(30));
  const auto result = run_thermodrift(dir, "fit --data ok.csv" + kSmallColumns + " --gyro-unit furlongs --out m.json");
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);
}

TEST_F(Workflow, FailedFitLeavesAnExistingModelUnchanged) {
  std::string text = small_log(50);
  text.replace(text.find("\n3,20,1\n") + 1, 6, "3,20,?");
  dir_.write("bad.csv", text);
  dir_.write("model.json", "old model\n");
  const auto result = run_thermodrift(dir_, "fit --data bad.csv" + kSmallColumns + " --out model.json");
  EXPECT_EQ(result.status, 3) << result.err;
  EXPECT_EQ(read_file(dir_.file("model.json")), "old model\n");
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"bad.csv", "model.json"}));
}

TEST_F(Workflow, CompensateFailingMidStreamLeavesNoOutput) {
  // Time goes backwards deep into the log, after thousands of rows have been written.
  auto lines = split_lines(read_file(cycle2_));
  const std::size_t bad = 15000;  // 0-based index into lines: file line 15001
  const auto comma = lines[bad].find(',');
  lines[bad] = "1" + lines[bad].substr(comma);  // t = 1 s
  std::string text;
  for (const auto& line : lines) text += line + "\n";
  dir_.write("in.csv", text);
  copy(model_, "model.json");
  auto result = run_thermodrift(dir_, "compensate --model model.json --data in.csv --out out.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "in.csv:15001:1: time goes backwards")) << result.err;
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"in.csv", "model.json"}));  // no out.csv, no temporary

  // An earlier output stays as it was.
  dir_.write("out.csv", "earlier result\n");
  result = run_thermodrift(dir_, "compensate --model model.json --data in.csv --out out.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  EXPECT_EQ(read_file(dir_.file("out.csv")), "earlier result\n");
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"in.csv", "model.json", "out.csv"}));
}

TEST_F(Workflow, OutputThatIsTheInputIsRefused) {
  const auto input = copy(cycle2_, "in.csv");
  copy(model_, "model.json");
  const std::string before = read_file(input);
  for (const std::string& out : std::vector<std::string>{"in.csv", "./in.csv", dir_.file("in.csv")}) {
    const auto result = run_thermodrift(dir_, "compensate --model model.json --data in.csv --out " + out);
    EXPECT_EQ(result.status, 2) << out << ": " << result.err;
    expect_one_line(result);
    EXPECT_TRUE(contains(result.err, "one of the inputs")) << result.err;
  }
  // The model is an input of compensate too.
  auto result = run_thermodrift(dir_, "compensate --model model.json --data in.csv --out model.json");
  EXPECT_EQ(result.status, 2) << result.err;
  // And the data is an input of fit.
  result = run_thermodrift(dir_, "fit --data in.csv" + kTemps + " --model linear --out in.csv");
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);
  EXPECT_EQ(read_file(input), before);
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"in.csv", "model.json"}));
}

TEST_F(Workflow, ModelFileErrorsAreExit3) {
  copy(cycle2_, "in.csv");
  const std::string text = read_file(model_);
  dir_.write("cut.json", text.substr(0, text.size() / 2));
  auto result = run_thermodrift(dir_, "evaluate --model cut.json --data in.csv --json");
  EXPECT_EQ(result.status, 3) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "cut.json:")) << result.err;
  EXPECT_TRUE(contains(result.err, "ends early")) << result.err;
  EXPECT_EQ(result.out, "");

  auto json = nlohmann::json::parse(text);
  json["version"] = 99;
  dir_.write("v99.json", json.dump());
  result = run_thermodrift(dir_, "evaluate --model v99.json --data in.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "version 99")) << result.err;

  result = run_thermodrift(dir_, "compensate --model v99.json --data in.csv --out out.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir_.file("out.csv")));
}

TEST_F(Workflow, ModelReadingColumnsTheDataLacksIsExit3) {
  // The same log with gyro_y renamed: the model's column is not there.
  std::string text = read_file(cycle2_);
  text.replace(text.find("gyro_y"), 6, "rate_y");
  dir_.write("renamed.csv", text);
  copy(model_, "model.json");
  const auto result = run_thermodrift(dir_, "evaluate --model model.json --data renamed.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  expect_one_line(result);
  EXPECT_TRUE(contains(result.err, "renamed.csv:1: no gyro column named 'gyro_y'")) << result.err;
}

// grad terms on the chamber air, given after the axes' own channels: the model names the
// extra column, compensate and evaluate read it by name, and a log without it is refused.
TEST_F(Workflow, GradTermsReadAnExtraTemperatureColumnByName) {
  copy(cycle1_, "cycle1.csv");
  copy(cycle2_, "cycle2.csv");
  const auto fit = run_thermodrift(dir_,
                                   "fit --data cycle1.csv --temp temp_x,temp_y,temp_z,temp_chamber --model linear "
                                   "--features dT,lag:600,grad:1-4,gradrate:1-4 --out grad.json --json");
  ASSERT_EQ(fit.status, 0) << fit.err;
  const auto model = nlohmann::json::parse(read_file(dir_.file("grad.json")));
  EXPECT_EQ(model.at("extra_temperature_columns"), nlohmann::json::array({"temp_chamber"}));
  EXPECT_EQ(model["axes"][2]["temperature_column"], "temp_z");

  const auto evaluated = run_thermodrift(dir_, "evaluate --model grad.json --data cycle2.csv --json");
  ASSERT_EQ(evaluated.status, 0) << evaluated.err;
  const auto all_axes = nlohmann::json::parse(evaluated.out)["axes"];
  for (const auto& axis : all_axes) {
    EXPECT_LT(axis.at("mse_after").get<double>(), axis.at("mse_before").get<double>()) << axis.dump();
  }
  // Its lag starts in equilibrium on a log begun mid-transient: evaluate says so, and
  // --settle leaves the first 1800 s out (1600 samples at 1 Hz after the 200 s warm-up).
  EXPECT_TRUE(contains(evaluated.err, "--settle 1800")) << evaluated.err;
  const auto settled = run_thermodrift(dir_, "evaluate --model grad.json --data cycle2.csv --settle 1800 --json");
  ASSERT_EQ(settled.status, 0) << settled.err;
  EXPECT_EQ(settled.err, "");
  const auto settled_json = nlohmann::json::parse(settled.out);
  EXPECT_EQ(settled_json["settle_seconds"], 1800.0);
  for (std::size_t a = 0; a < 3; ++a) {
    EXPECT_EQ(settled_json["axes"][a]["samples"].get<std::size_t>() + 1600, all_axes[a]["samples"].get<std::size_t>());
  }
  // A settle shorter than three times the lag: said too, with the settle that covers it.
  const auto short_settle = run_thermodrift(dir_, "evaluate --model grad.json --data cycle2.csv --settle 600 --json");
  ASSERT_EQ(short_settle.status, 0) << short_settle.err;
  EXPECT_TRUE(contains(short_settle.err, "slowest lag (600 s)")) << short_settle.err;
  EXPECT_TRUE(contains(short_settle.err, "--settle 1800 leaves it out")) << short_settle.err;
  EXPECT_TRUE(contains(short_settle.err, "the whole recording with --settle up to the part to judge"))
      << short_settle.err;
  const auto compensated = run_thermodrift(dir_, "compensate --model grad.json --data cycle2.csv --out out.csv");
  ASSERT_EQ(compensated.status, 0) << compensated.err;
  EXPECT_EQ(split_lines(read_file(dir_.file("out.csv"))).size(), split_lines(read_file(cycle2_)).size());

  // The axes' three columns only: the model's fourth is missing, said in one line.
  const auto short_of_one = run_thermodrift(dir_, "compensate --model grad.json --data cycle2.csv" + kTemps +
                                                      " --out short.csv");
  EXPECT_EQ(short_of_one.status, 2) << short_of_one.err;
  expect_one_line(short_of_one);
  EXPECT_TRUE(contains(short_of_one.err, "temp_chamber")) << short_of_one.err;
  EXPECT_FALSE(std::filesystem::exists(dir_.file("short.csv")));

  // A grad term reading a channel --temp does not give is a usage error.
  const auto beyond = run_thermodrift(dir_, "fit --data cycle1.csv" + kTemps + " --model linear --features dT,grad:1-4 "
                                                                                "--out beyond.json");
  EXPECT_EQ(beyond.status, 2) << beyond.err;
  expect_one_line(beyond);
  EXPECT_TRUE(contains(beyond.err, "temperature channel 4")) << beyond.err;
}

// The second cycle cut from the recording starts mid-transient, its lags in equilibrium
// where the unit's are not. `--log-start running` streams it after a ramp history, and
// `estimated` weighs that start by the settling rows; the figures of both come closer to the
// whole recording's on the same rows (the lags carried through the first cycle) than the
// cut log's started at power-on do.
TEST_F(Workflow, RunningAndEstimatedLogStartsComeCloserToTheWholeRecording) {
  copy(cycle1_, "cycle1.csv");
  copy(cycle2_, "cycle2.csv");
  copy(shared_->file("sim.csv"), "whole.csv");
  // A node of 600 s with its static map, rates and a memory, and a 2,000 s lag: terms whose
  // states the cut start sets (--features auto finds such sets, in minutes under the sanitizers).
  const auto fit = run_thermodrift(dir_, "fit --data cycle1.csv" + kTemps +
                                             " --model linear --features lag:600,hinge:600:-26.6,hinge:600:-1.6,"
                                             "hinge:600:23.4,lagrate:600,rate,dir:1000:600,lag:2000 --out node.json");
  ASSERT_EQ(fit.status, 0) << fit.err;
  const auto evaluate = [&](const std::string& options) {
    const auto result = run_thermodrift(dir_, "evaluate --model node.json --json " + options);
    EXPECT_EQ(result.status, 0) << result.err;
    return std::make_pair(nlohmann::json::parse(result.out), result.err);
  };
  const auto [cut, cut_err] = evaluate("--data cycle2.csv --settle 1800 --log-start power-on");
  const auto [running, running_err] = evaluate("--data cycle2.csv --settle 1800 --log-start running");
  const auto [whole, whole_err] =
      evaluate(fmt::format("--data whole.csv --settle {} --log-start power-on", kCycleSeconds + 1800));
  EXPECT_EQ(cut["log_start"], "power-on");
  EXPECT_EQ(running["log_start"], "running");
  EXPECT_TRUE(contains(cut_err, "--log-start running")) << cut_err;  // the settle warning names the remedy
  EXPECT_FALSE(contains(running_err, "equilibrium")) << running_err;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto samples = whole["axes"][a]["samples"].get<std::size_t>();
    EXPECT_EQ(cut["axes"][a]["samples"].get<std::size_t>(), samples);  // the same rows judged
    EXPECT_EQ(running["axes"][a]["samples"].get<std::size_t>(), samples);
    const double carried = whole["axes"][a]["mse_after"].get<double>();
    const double from_cut = std::abs(std::log(cut["axes"][a]["mse_after"].get<double>() / carried));
    const double from_running = std::abs(std::log(running["axes"][a]["mse_after"].get<double>() / carried));
    EXPECT_LT(from_running, from_cut) << "axis " << a << ": " << cut_err;
  }
  // Without --settle too, the same rows: the log's own warm-up stays out after a history.
  const auto [unsettled, unsettled_err] = evaluate("--data cycle2.csv");
  const auto [unsettled_running, unsettled_running_err] = evaluate("--data cycle2.csv --log-start running");
  for (std::size_t a = 0; a < 3; ++a) {
    EXPECT_EQ(unsettled_running["axes"][a]["samples"], unsettled["axes"][a]["samples"]);
  }
  // --log-start estimated: per axis, the weight of running's prediction that fits the
  // settling rows. On the cut log it comes closer to the whole recording than power-on does;
  // on a log that starts at power-on it changes next to nothing; without settling rows it is
  // power-on.
  const auto [estimated, estimated_err] = evaluate("--data cycle2.csv --settle 1800 --log-start estimated");
  const auto [on_whole, on_whole_err] = evaluate("--data whole.csv --settle 1800 --log-start power-on");
  const auto [estimated_whole, estimated_whole_err] = evaluate("--data whole.csv --settle 1800 --log-start estimated");
  const auto [estimated_unsettled, estimated_unsettled_err] = evaluate("--data cycle2.csv --log-start estimated");
  EXPECT_EQ(estimated["log_start"], "estimated");
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& weights = estimated["axes"][a]["running_weight"];
    ASSERT_EQ(weights.size(), 1u);
    EXPECT_GE(weights[0].get<double>(), 0.0);
    EXPECT_LE(weights[0].get<double>(), 1.0);
    EXPECT_EQ(estimated["axes"][a]["samples"], cut["axes"][a]["samples"]);
    const double carried = whole["axes"][a]["mse_after"].get<double>();
    const double from_cut = std::abs(std::log(cut["axes"][a]["mse_after"].get<double>() / carried));
    EXPECT_LT(std::abs(std::log(estimated["axes"][a]["mse_after"].get<double>() / carried)), from_cut) << "axis " << a;
    const double powered_on = on_whole["axes"][a]["mse_after"].get<double>();
    EXPECT_NEAR(estimated_whole["axes"][a]["mse_after"].get<double>(), powered_on, 0.05 * powered_on) << "axis " << a;
    EXPECT_EQ(estimated_unsettled["axes"][a]["running_weight"][0].get<double>(), 0.0);
    EXPECT_EQ(estimated_unsettled["axes"][a]["mse_after"], unsettled["axes"][a]["mse_after"]);
  }
  // libsvm-format data has no time to put a history before.
  dir_.write("one.libsvm", "0.5 1:0.1\n");
  for (const std::string start : {"running", "estimated"}) {
    const auto libsvm =
        run_thermodrift(dir_, "evaluate --model node.json --data one.libsvm --format libsvm --log-start " + start);
    EXPECT_EQ(libsvm.status, 2) << libsvm.err;
    expect_one_line(libsvm);
  }
}

}  // namespace
}  // namespace thermodrift
