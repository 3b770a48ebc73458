// Logs as they come off the bench (issue 14): time in ms or as ISO 8601 stamps, raw
// counts scaled to °C and °/h. Each is the simulated log rewritten; each must give the
// model the simulated log gives, and evaluate, compensate and export must read the raw
// log with the model alone.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
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
// The raw-count unit of the issue: °C = 0.00390625·raw - 231, gyro in rad/s halved.
const std::string kRawOptions = " --temp-scale 0.00390625 --temp-offset -231 --gyro-unit radps --gyro-scale 0.5";
constexpr double kTemperatureScale = 0.00390625;
constexpr double kTemperatureOffset = -231;
constexpr double kGyroScale = 0.5;
const double kRadiansPerSecondInDegreesPerHour = 3600.0 * 180.0 / std::numbers::pi;

using testing::contains;

using testing::cells_of;
std::string join(const std::vector<std::string>& cells) { return testing::join_cells(cells); }

// 2026-03-07T15:45:00Z plus `seconds`, written in one of four forms by row: Z with a
// fraction, an offset with a colon, a space and no fraction nor zone, an offset without colon.
std::string iso_stamp(double seconds, std::size_t row) {
  using namespace std::chrono;
  const auto whole = static_cast<long long>(std::floor(seconds));
  const auto millis = static_cast<long long>(std::llround((seconds - static_cast<double>(whole)) * 1000));
  const sys_seconds start = sys_days{year{2026} / March / 7} + hours{15} + minutes{45};
  auto civil = [&](int offset_minutes) {
    const sys_seconds local = start + std::chrono::seconds{whole} + minutes{offset_minutes};
    const sys_days day = floor<days>(local);
    const year_month_day date{day};
    const hh_mm_ss time{local - day};
    return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}", static_cast<int>(date.year()),
                       static_cast<unsigned>(date.month()), static_cast<unsigned>(date.day()), time.hours().count(),
                       time.minutes().count(), time.seconds().count());
  };
  switch (row % 4) {
    case 0: return fmt::format("{}.{:03}Z", civil(0), millis);
    case 1: return fmt::format("{}.{:03}+01:00", civil(60), millis);
    case 2: {
      std::string text = civil(0);  // no zone: read as UTC
      text[10] = ' ';
      return millis == 0 ? text : fmt::format("{}.{:03}Z", civil(0), millis);
    }
    default: return fmt::format("{}.{:03}000-0530", civil(-330), millis);
  }
}

// Every number in `a` within `tolerance` (relative, at least absolute) of `b`'s.
void expect_numbers_near(const nlohmann::json& a, const nlohmann::json& b, double tolerance, const std::string& where) {
  ASSERT_EQ(a.type(), b.type()) << where;
  if (a.is_number()) {
    const double x = a.get<double>(), y = b.get<double>();
    EXPECT_NEAR(x, y, tolerance * std::max(1.0, std::abs(y))) << where;
  } else if (a.is_array() || a.is_object()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (auto it = a.begin(); it != a.end(); ++it) {
      const std::string key = a.is_object() ? it.key() : std::to_string(std::distance(a.begin(), it));
      expect_numbers_near(*it, a.is_object() ? b.at(it.key()) : b.at(std::distance(a.begin(), it)), tolerance,
                          where + "/" + key);
    }
  } else {
    EXPECT_EQ(a, b) << where;
  }
}

nlohmann::json model_file(const TempDir& dir, const std::string& name) {
  return nlohmann::json::parse(read_file(dir.file(name)));
}

// One simulated cycle at 1 Hz and its rewrites: time in ms, time as ISO 8601 stamps,
// temperatures and gyro as raw counts; the linear model of each.
class BenchLogs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>();
    ASSERT_EQ(run_thermodrift(*dir_, "simulate --cycles 1 --out s.csv").status, 0);
    const auto lines = split_lines(read_file(dir_->file("s.csv")));
    const auto header = cells_of(lines.front());
    ASSERT_EQ(header[0], "time_s");
    std::string ms = lines.front() + "\n", iso = ms, raw = ms;
    for (std::size_t i = 1; i < lines.size(); ++i) {
      auto cells = cells_of(lines[i]);
      const double time = std::stod(cells[0]);
      auto rewritten = cells;
      rewritten[0] = fmt::format("{}", std::llround(time * 1000));
      ms += join(rewritten) + "\n";
      rewritten[0] = iso_stamp(time, i);
      iso += join(rewritten) + "\n";
      rewritten = cells;
      for (std::size_t c = 0; c < header.size(); ++c) {
        if (header[c] == "temp_x" || header[c] == "temp_y" || header[c] == "temp_z") {
          rewritten[c] = fmt::format("{:.17g}", (std::stod(cells[c]) - kTemperatureOffset) / kTemperatureScale);
        } else if (header[c].starts_with("gyro_")) {
          rewritten[c] = fmt::format("{:.17g}", std::stod(cells[c]) / kRadiansPerSecondInDegreesPerHour / kGyroScale);
        }
      }
      raw += join(rewritten) + "\n";
    }
    dir_->write("ms.csv", ms);
    dir_->write("iso.csv", iso);
    dir_->write("raw.csv", raw);
    for (const auto& [name, options] : {std::pair{"s", ""}, {"ms", " --time-unit ms"}, {"iso", ""}, {"raw", kRawOptions.c_str()}}) {
      const auto fit = run_thermodrift(
          *dir_, fmt::format("fit --data {}.csv{}{} --model linear --out {}.json", name, kColumns, options, name));
      ASSERT_EQ(fit.status, 0) << name << ": " << fit.err;
    }
  }
  static void TearDownTestSuite() { dir_.reset(); }

  // The fitted numbers of a model file: each axis' pipeline and model.
  static nlohmann::json fitted(const std::string& name) {
    nlohmann::json axes = nlohmann::json::array();
    const nlohmann::json model = model_file(*dir_, name);
    for (const auto& axis : model.at("axes")) {
      axes.push_back({{"pipeline", axis["pipeline"]}, {"model", axis["model"]}});
    }
    return axes;
  }

  static std::unique_ptr<TempDir> dir_;
};
std::unique_ptr<TempDir> BenchLogs::dir_;

TEST_F(BenchLogs, MillisecondLogGivesTheModelOfTheLogInSeconds) {
  ASSERT_EQ(fitted("s.json").size(), 3u);
  EXPECT_EQ(fitted("ms.json"), fitted("s.json"));
  EXPECT_EQ(model_file(*dir_, "ms.json")["time_unit"], "ms");
  EXPECT_FALSE(model_file(*dir_, "s.json").contains("time_unit"));
}

TEST_F(BenchLogs, IsoTimestampLogGivesTheModelOfTheLogInSeconds) {
  EXPECT_TRUE(contains(read_file(dir_->file("iso.csv")), "2026-03-07 15:45:01,")) << "a form is not exercised";
  expect_numbers_near(fitted("iso.json"), fitted("s.json"), 1e-6, "iso");
  const auto coefficients = fitted("iso.json").at(0).at("model").at("coefficients");
  ASSERT_GT(coefficients.size(), 0u);
  EXPECT_NE(coefficients[0].get<double>(), 0.0);
}

TEST_F(BenchLogs, RawCountLogGivesTheModelOfTheConvertedLog) {
  expect_numbers_near(fitted("raw.json"), fitted("s.json"), 1e-6, "raw");
  const auto scaling = model_file(*dir_, "raw.json")["scaling"];
  EXPECT_EQ(scaling["temperature_scale"], nlohmann::json::array({kTemperatureScale}));
  EXPECT_EQ(scaling["temperature_offset"], nlohmann::json::array({kTemperatureOffset}));
  EXPECT_EQ(scaling["gyro_scale"], nlohmann::json::array({kGyroScale}));
  EXPECT_EQ(model_file(*dir_, "raw.json")["gyro_unit"], "radps");
  EXPECT_FALSE(model_file(*dir_, "s.json").contains("scaling"));
}

// The model knows how its log reads: no option repeated.
TEST_F(BenchLogs, EvaluateReadsTheRawLogWithTheModelAlone) {
  const auto raw = run_thermodrift(*dir_, "evaluate --model raw.json --data raw.csv --json");
  ASSERT_EQ(raw.status, 0) << raw.err;
  const auto converted = run_thermodrift(*dir_, "evaluate --model s.json --data s.csv --json");
  ASSERT_EQ(converted.status, 0) << converted.err;
  const auto raw_axes = nlohmann::json::parse(raw.out)["axes"];
  const auto converted_axes = nlohmann::json::parse(converted.out)["axes"];
  ASSERT_EQ(raw_axes.size(), 3u);
  for (std::size_t a = 0; a < 3; ++a) {
    for (const char* key : {"mse_before", "mse_after", "samples"}) {
      EXPECT_NEAR(raw_axes[a][key].get<double>(), converted_axes[a][key].get<double>(),
                  1e-6 * converted_axes[a][key].get<double>())
          << a << " " << key;
    }
  }
}

TEST_F(BenchLogs, CompensateEchoesRawRowsAndAgreesWithTheConvertedLog) {
  for (const auto& [model, data] : {std::pair{"raw", "raw"}, {"s", "s"}, {"iso", "iso"}}) {
    const auto run = run_thermodrift(
        *dir_, fmt::format("compensate --model {}.json --data {}.csv --out {}_out.csv", model, data, data));
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_TRUE(contains(run.err, fmt::format("{}.csv: 200 of 22800 rows not ready (warm-up / gaps)", data))) << run.err;
    EXPECT_FALSE(contains(run.err, "warning")) << run.err;
  }
  const auto input = split_lines(read_file(dir_->file("raw.csv")));
  const auto raw = split_lines(read_file(dir_->file("raw_out.csv")));
  const auto converted = split_lines(read_file(dir_->file("s_out.csv")));
  const auto iso_in = split_lines(read_file(dir_->file("iso.csv")));
  const auto iso = split_lines(read_file(dir_->file("iso_out.csv")));
  ASSERT_EQ(raw.size(), converted.size());
  ASSERT_EQ(raw.size(), input.size());
  ASSERT_EQ(iso.size(), input.size());
  double largest = 0;
  for (std::size_t i = 1; i < raw.size(); ++i) {
    ASSERT_TRUE(raw[i].starts_with(input[i] + ",")) << "row " << i << " not echoed: " << raw[i];
    ASSERT_TRUE(iso[i].starts_with(iso_in[i] + ",")) << "row " << i << " not echoed: " << iso[i];
    const auto a = cells_of(raw[i]), b = cells_of(converted[i]), c = cells_of(iso[i]);
    for (std::size_t k = 1; k <= 3; ++k) {
      const double expected = std::stod(b[b.size() - k]);
      largest = std::max({largest, std::abs(std::stod(a[a.size() - k]) - expected),
                          std::abs(std::stod(c[c.size() - k]) - expected)});
    }
  }
  EXPECT_LT(largest, 1e-6);
}

// A log in ms read as s: every step is 1000 s, longer than the gap threshold.
TEST_F(BenchLogs, CompensateSaysWhyALogWasNeverReady) {
  const auto run = run_thermodrift(*dir_, "compensate --model s.json --data ms.csv --out never.csv");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(contains(run.err, "thermodrift: warning: compensate: gyro_x: never ready: all 22800 rows")) << run.err;
  EXPECT_TRUE(contains(run.err, "every time step was a gap")) << run.err;
  EXPECT_TRUE(contains(run.err, "check --time-unit")) << run.err;
  EXPECT_TRUE(contains(run.err, "ms.csv: 22800 of 22800 rows not ready (warm-up / gaps)")) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 2) << run.err;

  // The option on the command line takes over the model's unit: then it is ready.
  const auto fixed = run_thermodrift(*dir_, "compensate --model s.json --data ms.csv --time-unit ms --out fixed.csv");
  ASSERT_EQ(fixed.status, 0) << fixed.err;
  EXPECT_TRUE(contains(fixed.err, "ms.csv: 200 of 22800 rows not ready")) << fixed.err;

  // A log in s read as ms lasts 22.8 s: shorter than the warm-up.
  const auto short_run =
      run_thermodrift(*dir_, "compensate --model s.json --data s.csv --time-unit ms --out short.csv");
  ASSERT_EQ(short_run.status, 0) << short_run.err;
  EXPECT_TRUE(contains(short_run.err, "shorter than the 200 s warm-up")) << short_run.err;
}

TEST_F(BenchLogs, ExportedHeaderOfARawModelSaysItTakesRawValues) {
  ASSERT_EQ(run_thermodrift(*dir_, "export --model raw.json --out raw.h").status, 0);
  ASSERT_EQ(run_thermodrift(*dir_, "export --model s.json --out s.h").status, 0);
  const std::string raw = read_file(dir_->file("raw.h"));
  const std::string plain = read_file(dir_->file("s.h"));
  EXPECT_TRUE(contains(raw, "#define THERMODRIFT_RAW_INPUTS 1")) << raw.substr(0, 2000);
  EXPECT_TRUE(contains(raw, "const double gyro_raw[THERMODRIFT_AXES]"));
  EXPECT_TRUE(contains(plain, "#define THERMODRIFT_RAW_INPUTS 0"));
  EXPECT_FALSE(contains(plain, "gyro_raw"));
}

TEST_F(BenchLogs, BadScalingIsAUsageError) {
  for (const std::string options : {" --temp-scale 0", " --gyro-scale 0", " --temp-scale 1,2", " --gyro-scale inf",
                                    " --time-unit min"}) {
    const auto run = run_thermodrift(*dir_, "fit --data s.csv" + kColumns + options + " --model linear --out bad.json");
    EXPECT_EQ(run.status, 2) << options << ": " << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_->file("bad.json")));
}

}  // namespace
}  // namespace thermodrift
