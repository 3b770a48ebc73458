// Unclear messages from issue 18, each said for what it is: an empty list item, one gyro
// column twice, a number list or a whole number that is not one, a decimation that leaves
// too few samples, a CR-only or UTF-16 file, and
// nlohmann's exception tags in model-file errors.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

using testing::contains;

class ClearMessages : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(run_thermodrift(dir_, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  }
  // Runs `arguments`, expects `status`, one line on stderr holding `part`, and no m.json.
  void expect_refused(const std::string& arguments, int status, const std::string& part) {
    SCOPED_TRACE(arguments);
    const auto result = run_thermodrift(dir_, arguments);
    EXPECT_EQ(result.status, status) << result.err;
    EXPECT_TRUE(contains(result.err, part)) << result.err;
    EXPECT_EQ(split_lines(result.err).size(), 1u) << result.err;
    EXPECT_FALSE(contains(result.err, "[json.exception")) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir_.file("m.json")));
  }
  TempDir dir_;
};

TEST_F(ClearMessages, EmptyListItemsAndAGyroColumnTwice) {
  const std::string fit = "fit --data log.csv --temp temp_x --model linear --out m.json ";
  expect_refused(fit + "--gyro gyro_x --features ,", 2, "--features: expected names separated by single commas, not ','");
  expect_refused(fit + "--gyro gyro_x,,gyro_y", 2, "--gyro: expected names separated by single commas, not 'gyro_x,,gyro_y'");
  expect_refused(fit + "--gyro gyro_x,gyro_x", 2, "--gyro names column gyro_x twice ('gyro_x' and 'gyro_x')");
  expect_refused(fit + "--gyro gyro_x,6", 2, "--gyro names column gyro_x twice ('gyro_x' and '6')");
  EXPECT_EQ(run_thermodrift(dir_, fit + "--gyro gyro_x --gyro gyro_y").status, 0);  // one flag per column still works
}

// A header naming gyro_x twice: fit found both columns by their prefix and wrote two axes
// reading column gyro_x, a model evaluate and compensate then refused as a usage error.
// Every command reading the log refuses it as bad data, naming the header line.
TEST_F(ClearMessages, AHeaderNamingAColumnTwice) {
  ASSERT_EQ(run_thermodrift(dir_, "fit --data log.csv --temp temp_x,temp_y,temp_z --model linear --out good.json").status, 0);
  std::string text = read_file(dir_.file("log.csv"));
  text.replace(text.find("gyro_y"), 6, "gyro_x");
  dir_.write("twice.csv", text);
  const std::string said = "twice.csv:1:7: the header names 'gyro_x' twice (columns 6 and 7)";
  expect_refused("fit --data twice.csv --temp temp_x,temp_y,temp_z --model linear --out m.json", 3, said);
  expect_refused("evaluate --model good.json --data twice.csv", 3, said);
  expect_refused("compensate --model good.json --data twice.csv --out c.csv", 3, said);
  EXPECT_FALSE(std::filesystem::exists(dir_.file("c.csv")));
}

// A log whose thermometers never move (a 999.9 °C soak): --features auto found columns
// of almost nothing and coefficients beyond 1e12, and fit failed at saving with exit 1, as
// if the tool had failed. It is the data: exit 3, naming the span and the remedy.
TEST_F(ClearMessages, FeaturesAutoOnAConstantTemperature) {
  std::string text = read_file(dir_.file("log.csv"));
  const auto lines = split_lines(text);
  std::string constant = lines.front() + "\n";
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::vector<std::string> cells;
    for (std::size_t begin = 0;;) {
      const auto end = lines[i].find(',', begin);
      cells.push_back(lines[i].substr(begin, end - begin));
      if (end == std::string::npos) break;
      begin = end + 1;
    }
    for (std::size_t c = 1; c <= 4; ++c) cells[c] = "999.9";  // temp_chamber, temp_x, temp_y, temp_z
    for (std::size_t c = 0; c < cells.size(); ++c) constant += (c == 0 ? "" : ",") + cells[c];
    constant += "\n";
  }
  dir_.write("soak.csv", constant);
  expect_refused("fit --data soak.csv --temp temp_x,temp_y,temp_z --model linear --features auto --out m.json", 3,
                 "soak.csv: axis 1: its temperature spans 0 °C (999.9 to 999.9): --features auto needs a log whose "
                 "temperature moves by at least 1 °C");
}

// Numbers in a list: an empty item was dropped (two scales for three columns), and a
// word or NaN is named for what it is.
TEST_F(ClearMessages, EmptyOrJunkItemsInNumberLists) {
  const std::string fit = "fit --data log.csv --gyro gyro_x,gyro_y,gyro_z --temp temp_x,temp_y,temp_z --model linear --out m.json ";
  expect_refused(fit + "--temp-scale 1,,2", 2, "--temp-scale: expected numbers separated by single commas, not '1,,2'");
  expect_refused(fit + "--gyro-scale 1,", 2, "--gyro-scale: expected numbers separated by single commas, not '1,'");
  expect_refused(fit + "--temp-offset 0,x,0", 2, "--temp-offset: expected a finite number, not 'x'");
  expect_refused(fit + "--temp-offset 0,nan,0", 2, "--temp-offset: expected a finite number, not 'nan'");
  EXPECT_EQ(run_thermodrift(dir_, fit + "--temp-scale 1,1,1 --gyro-scale 1").status, 0);
}

// Whole-number options: CLI11 answered `--decimate 1e9` with "Could not convert", and took
// `--seed -1` or a seed beyond 64 bits as some other seed without a word.
TEST_F(ClearMessages, WholeNumberOptionsSayWhatTheyTake) {
  const std::string fit = "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json ";
  expect_refused(fit + "--decimate 1e9", 2, "--decimate: expected a whole number from 1 to 1000000000, not '1e9'");
  expect_refused(fit + "--seed -1", 2, "--seed: expected a whole number from 0 to 18446744073709551615, not '-1'");
  expect_refused(fit + "--seed 18446744073709551616", 2, "not '18446744073709551616'");
  expect_refused(fit + "--threads 0", 2, "--threads: expected a whole number from 1 to 1024, not '0'");
  const std::string svr = "fit --data log.csv --gyro gyro_x --temp temp_x --model svr --out m.json ";
  expect_refused(svr + "--evaluations 0", 2, "--evaluations: expected a whole number from 1 to 1000000, not '0'");
  expect_refused(svr + "--folds 2.5", 2, "--folds: expected a whole number from 2 to 100, not '2.5'");
  expect_refused("simulate --out m.json --law -3", 2, "--law: expected a whole number from 0 to");
  expect_refused("simulate --out m.json --cycles 2.5", 2, "--cycles: expected a whole number from 1 to 1000, not '2.5'");
}

TEST_F(ClearMessages, ADecimationThatLeavesTooFewSamplesSaysSo) {
  expect_refused("fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json --decimate 100000", 3,
                 "keeping one ready sample in 100000: 1 usable sample, at least 4 needed; the longest log spans "
                 "22790 s (a smaller --decimate helps)");
}

TEST_F(ClearMessages, CrOnlyAndUtf16FilesAreNamed) {
  const std::string log = read_file(dir_.file("log.csv"));
  std::string cr = log;
  std::replace(cr.begin(), cr.end(), '\n', '\r');
  dir_.write("cr.csv", cr);
  std::string utf16 = "\xFF\xFE";
  for (char c : log) utf16 += std::string{c, '\0'};
  dir_.write("u16.csv", utf16);
  const std::string options = " --gyro gyro_x --temp temp_x --model linear --out m.json";
  expect_refused("fit --data cr.csv" + options, 3, "cr.csv:1:86: a line ends in CR alone");
  expect_refused("fit --data u16.csv" + options, 3, "u16.csv:1:1: a NUL byte or a UTF-16 byte-order mark");
}

TEST_F(ClearMessages, ModelFileErrorsCarryNoJsonExceptionTags) {
  ASSERT_EQ(run_thermodrift(dir_, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out good.json").status, 0);
  std::string text = read_file(dir_.file("good.json"));
  const auto at = text.find("\"gyro_unit\": \"dph\"");
  ASSERT_NE(at, std::string::npos);
  dir_.write("unit.json", std::string(text).replace(at, 18, "\"gyro_unit\": 5"));
  // Named at the value refused (the replacements keep every line and column before them).
  auto position = [&](std::size_t offset) {
    const auto line_start = text.rfind('\n', offset);
    return fmt::format("{}:{}", 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'),
                       offset - line_start);
  };
  expect_refused("evaluate --model unit.json --data log.csv", 3,
                 "unit.json:" + position(at + 13) + ": invalid model file: type must be string, but is number");
  const auto name = text.find("\"name\": \"gyro_x\"");
  ASSERT_NE(name, std::string::npos);
  dir_.write("name.json", std::string(text).replace(name, 16, "\"name\": []"));
  expect_refused("evaluate --model name.json --data log.csv", 3,
                 "name.json:" + position(name + 8) + ": axis 1: type must be string, but is array");
}

}  // namespace
}  // namespace thermodrift::testing
