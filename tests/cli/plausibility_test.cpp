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

// evaluate, compensate and export of `model` (on log.csv in `dir`) each refuse it at load:
// exit 3, one line containing `message`, and no output written.
void expect_refused_at_load(const TempDir& dir, const std::string& model, const std::string& message) {
  for (const std::string command : {"evaluate --model " + model + " --data log.csv",
                                    "compensate --model " + model + " --data log.csv --out c.csv",
                                    "export --model " + model + " --out m.h"}) {
    SCOPED_TRACE(command);
    const auto result = run_thermodrift(dir, command);
    EXPECT_EQ(result.status, 3) << result.err;
    EXPECT_TRUE(contains(result.err, message)) << result.err;
    EXPECT_TRUE(contains(result.err, model + ":")) << result.err;  // then the value's line and column
    EXPECT_EQ(split_lines(result.err).size(), 1u) << result.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.h")));
}

// log.csv (one cycle at 0.1 Hz) simulated in `dir`, m.json fitted on its x axis with
// `model` (the --model options), and the file's text.
std::string fitted_model_text(const TempDir& dir, const std::string& model) {
  EXPECT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  EXPECT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model " + model + " --out m.json").status, 0);
  return read_file(dir.file("m.json"));
}

// `text` with the first number after `key` replaced by `value`.
std::string with_number_after(std::string text, const std::string& key, const std::string& value) {
  const auto at = text.find(key);
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return text;
  const auto begin = text.find_first_of("-0123456789", at + key.size());
  return text.replace(begin, text.find_first_of(",\n]}", begin) - begin, value);
}

TEST(Plausibility, AModelWithAbsurdNumbersIsRefusedAtLoad) {
  TempDir dir;
  dir.write("huge.json", with_number_after(fitted_model_text(dir, "linear"), "\"intercept\": ", "1e308"));
  expect_refused_at_load(dir, "huge.json", ": axis 1: model.intercept is 1e+308, beyond");
  // Within ±1e12 but no temperature: a reference of 1e11 °C made compensate write 1.6e12 °/h.
  dir.write("hot.json", with_number_after(read_file(dir.file("m.json")), "\"reference_temperature\": ", "1e11"));
  const auto result = run_thermodrift(dir, "compensate --model hot.json --data log.csv --out c.csv");
  EXPECT_EQ(result.status, 3) << result.err;
  EXPECT_TRUE(contains(result.err, "reference temperature 1e+11 °C is beyond -273.15..1000 °C")) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv")));
}

// Fuzzing found a model file with an extra key holding arrays nested 30,000 deep: every
// command loading it died of a stack overflow, and compensate left its empty temporary
// output (.c.csv.tmp-XXXXXX) behind.
TEST(Plausibility, ADeeplyNestedModelIsRefusedAndLeavesNothing) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model svr --C 10 --sigma 1 --out m.json").status, 0);
  std::string text = read_file(dir.file("m.json"));
  text.insert(text.find("\"format\""), "\"x\": " + std::string(30000, '[') + std::string(30000, ']') + ", ");
  dir.write("deep.json", text);
  const auto before = dir.entries();
  for (const std::string command : {"evaluate --model deep.json --data log.csv",
                                    "compensate --model deep.json --data log.csv --out c.csv",
                                    "export --model deep.json --out m.h", "compress --model deep.json --out small.json"}) {
    SCOPED_TRACE(command);
    const auto result = run_thermodrift(dir, command);
    EXPECT_EQ(result.status, 3) << result.err;
    EXPECT_TRUE(contains(result.err, "deep.json:")) << result.err;
    EXPECT_TRUE(contains(result.err, "arrays or objects nested more than 100 deep")) << result.err;
    EXPECT_EQ(split_lines(result.err).size(), 1u) << result.err;
    EXPECT_EQ(dir.entries(), before);
  }
}

// A subnormal feature_scale (5e-324) loaded: evaluate printed NaN metrics, compensate
// wrote NaN in every row and export put it in the C header, all with exit 0.
TEST(Plausibility, ASubnormalScaleIsRefusedAtLoad) {
  TempDir dir;
  dir.write("tiny.json",
            with_number_after(fitted_model_text(dir, "svr --C 10 --sigma 1"), "\"feature_scale\": [", "5e-324"));
  expect_refused_at_load(dir, "tiny.json",
                         ": axis 1: model.feature_scale[0] is 4.94066e-324: a scale must be at least 1e-12");
}

// A model whose prediction overflows on a log inside the physical ranges (here a term
// dT^400): compensate wrote "-inf", a number to a reader. Such a row is flagged not ready
// (1) as the Compensator and the exported step flag it, and its value is NaN.
TEST(Plausibility, ACompensatedValueThatIsNotFiniteIsNanAndFlaggedNotReady) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --features dT --out m.json").status, 0);
  std::string huge = "dT^4";
  for (int i = 1; i < 100; ++i) huge += "*dT^4";
  std::string text = read_file(dir.file("m.json"));
  for (std::size_t at = text.find("\"dT\""); at != std::string::npos; at = text.find("\"dT\"", at)) {
    text.replace(at, 4, "\"" + huge + "\"");
    at += huge.size();
  }
  dir.write("overflow.json", text);
  const auto result = run_thermodrift(dir, "compensate --model overflow.json --data log.csv --out c.csv --flags");
  ASSERT_EQ(result.status, 0) << result.err;
  const auto lines = split_lines(read_file(dir.file("c.csv")));
  const auto header = cells_of(lines.front());
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::size_t not_finite = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto cells = cells_of(lines[i]);
    const std::string& value = cells.at(column("gyro_x_comp_dph"));
    EXPECT_FALSE(contains(value, "inf")) << "line " << i + 1 << ": " << lines[i];
    if (value != "nan") continue;
    ++not_finite;
    EXPECT_EQ(std::stoi(cells.at(column("gyro_x_flags"))) & 1, 1) << "line " << i + 1 << ": " << lines[i];
  }
  EXPECT_GT(not_finite, 100u);
}

// 5,000 terms per axis took minutes to evaluate (a linear model costs terms × regressors
// per sample) and ignored Ctrl-C meanwhile. The loader refuses more than 256, and fit
// refuses them before fitting, so it never writes what would not load.
TEST(Plausibility, TooManyTermsPerAxisAreRefusedByFitAndAtLoad) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  std::string terms = "lag:1";
  for (int tau = 2; tau <= 257; ++tau) terms += ",lag:" + std::to_string(tau);
  const auto fit = run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --features " +
                                            terms + " --out m.json");
  EXPECT_EQ(fit.status, 2) << fit.err;
  EXPECT_TRUE(contains(fit.err, "257 feature terms for one axis; at most 256 are allowed")) << fit.err;
  EXPECT_EQ(split_lines(fit.err).size(), 1u) << fit.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));

  terms.erase(terms.rfind(','));  // 256
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --features " + terms +
                                     " --out m.json").status, 0);
  // One term more in the pipeline: the loader counts them before it reads the rest.
  std::string text = read_file(dir.file("m.json"));
  const auto terms_at = text.find("\"terms\": [", text.find("\"pipeline\""));
  ASSERT_NE(terms_at, std::string::npos);
  text.insert(terms_at + 10, "\"lag:9999\", ");
  dir.write("many.json", text);
  const auto evaluate = run_thermodrift(dir, "evaluate --model many.json --data log.csv");
  EXPECT_EQ(evaluate.status, 3) << evaluate.err;
  EXPECT_TRUE(contains(evaluate.err, ": axis 1: 257 feature terms for one axis; at most 256 are allowed"))
      << evaluate.err;
}

}  // namespace
}  // namespace thermodrift::testing
