// Reading whole chamber logs: columns by name and index, units, the real BMI270 logs, and
// every data error with its line and column.
#include "thermodrift/io/chamber_log.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "../../support/shared_data.hpp"
#include "../../support/temp_dir.hpp"
#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

using testing::TempDir;

using testing::contains;

LogSpec named_spec() {
  LogSpec spec;
  spec.time_column = "time_s";
  spec.gyro_columns = {"gyro_x"};
  spec.temperature_columns = {"temp"};
  return spec;
}

// The DataError reading `path` with `spec` throws; fails the test if none.
DataError log_error(const std::string& path, const LogSpec& spec) {
  try {
    read_chamber_log(path, spec);
  } catch (const DataError& error) {
    return error;
  }
  ADD_FAILURE() << "no DataError reading " << path;
  return DataError("", 0, 0, "");
}

const std::string kHeader = "time_s,temp,gyro_x\n";

TEST(ChamberLog, ColumnsByName) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time_s,temp,gyro_x,gyro_y\n0,20,1.5,9\n0.5,21,2.5,9\n");
  const ChamberLog log = read_chamber_log(path, named_spec());
  ASSERT_EQ(log.rows(), 2u);
  ASSERT_EQ(log.axes(), 1u);
  EXPECT_EQ(log.time, (std::vector<double>{0, 0.5}));
  EXPECT_EQ(log.gyro[0], (std::vector<double>{1.5, 2.5}));
  EXPECT_EQ(log.temperature[0], (std::vector<double>{20, 21}));
  EXPECT_EQ(log.gyro_names, (std::vector<std::string>{"gyro_x"}));
  EXPECT_EQ(log.temperature_names, (std::vector<std::string>{"temp"}));
  EXPECT_EQ(log.line, (std::vector<std::size_t>{2, 3}));
  EXPECT_EQ(log.source, path);
}

TEST(ChamberLog, ColumnsByOneBasedIndexWithoutHeader) {
  TempDir dir;
  const auto path = dir.write("log.csv", "20,0,1.5,7\n21,1,2.5,8\n22,2,3.5,9\n");
  LogSpec spec;
  spec.time_column = "2";
  spec.gyro_columns = {"4", "3"};
  spec.temperature_columns = {"1"};
  const ChamberLog log = read_chamber_log(path, spec);
  ASSERT_EQ(log.rows(), 3u);
  EXPECT_EQ(log.time, (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(log.gyro[0], (std::vector<double>{7, 8, 9}));
  EXPECT_EQ(log.gyro[1], (std::vector<double>{1.5, 2.5, 3.5}));
  EXPECT_EQ(log.temperature[0], (std::vector<double>{20, 21, 22}));
  EXPECT_EQ(log.gyro_names, (std::vector<std::string>{"column 4", "column 3"}));
}

TEST(ChamberLog, ColumnsByIndexWithHeaderAndDefaultsByPrefix) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time_s,temp_a,temp_b,gyro_x,gyro_y\n0,1,2,3,4\n1,1,2,3,4\n");
  LogSpec spec;
  spec.gyro_columns = {"5"};
  spec.temperature_columns = {"3"};
  const ChamberLog by_index = read_chamber_log(path, spec);
  EXPECT_EQ(by_index.gyro[0][0], 4);
  EXPECT_EQ(by_index.temperature[0][0], 2);
  EXPECT_EQ(by_index.gyro_names, (std::vector<std::string>{"gyro_y"}));

  const ChamberLog defaults = read_chamber_log(path, LogSpec{});  // time_s, gyro*, temp*
  EXPECT_EQ(defaults.axes(), 2u);
  EXPECT_EQ(defaults.temperature.size(), 2u);
  EXPECT_EQ(defaults.time, (std::vector<double>{0, 1}));
}

// A bench logger's header: time_ms, Temp_raw, Gyro_X... — found by name in any case; the
// time column's unit is still --time-unit's.
TEST(ChamberLog, BenchHeadersAreFoundInAnyCase) {
  TempDir dir;
  const auto path = dir.write("log.csv", "Index,Time_ms,Temp_raw,Gyro_X,Gyro_Y\n7,1000,5,3,4\n8,1500,5,3,4\n");
  LogSpec spec;
  spec.time_unit = TimeUnit::ms;
  const ChamberLog log = read_chamber_log(path, spec);
  EXPECT_EQ(log.time, (std::vector<double>{0, 0.5}));
  EXPECT_EQ(log.gyro_names, (std::vector<std::string>{"Gyro_X", "Gyro_Y"}));
  EXPECT_EQ(log.temperature_names, (std::vector<std::string>{"Temp_raw"}));
  // An exact time_s, time or t comes before a time* name; "temperature" is no time column.
  const auto both = dir.write("both.csv", "timestamp,temperature,t,gyro\n9,1,0,2\n9,1,1,2\n");
  EXPECT_EQ(read_chamber_log(both, LogSpec{}).time, (std::vector<double>{0, 1}));
  const auto none = dir.write("none.csv", "temperature,gyro\n1,2\n1,2\n");
  EXPECT_THROW(read_chamber_log(none, LogSpec{}), UsageError);
}

// Found by prefix, three temp* columns for two axes cannot be paired by file order (the
// first might be the chamber air): a usage error naming them. Named with --temp, the
// columns after one per axis load as extra channels.
TEST(ChamberLog, MoreTempColumnsThanAxesMustBeNamed) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time_s,temp_chamber,temp_a,temp_b,gyro_x,gyro_y\n0,9,1,2,3,4\n1,9,1,2,3,4\n");
  try {
    read_chamber_log(path, LogSpec{});
    ADD_FAILURE() << "three temp* columns for two axes were paired by order";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("temp_chamber,temp_a,temp_b"), std::string::npos) << error.what();
  }
  LogSpec spec;
  spec.temperature_columns = {"temp_a", "temp_b", "temp_chamber"};
  const ChamberLog named = read_chamber_log(path, spec);
  EXPECT_EQ(named.temperature_names, (std::vector<std::string>{"temp_a", "temp_b", "temp_chamber"}));
  EXPECT_EQ(named.temperature[2][0], 9);
}

TEST(ChamberLog, RateGivesTimeWithoutATimeColumn) {
  TempDir dir;
  const auto path = dir.write("log.csv", "20,1\n20,2\n20,3\n20,4\n");
  LogSpec spec;
  spec.rate_hz = 50;
  spec.gyro_columns = {"2"};
  spec.temperature_columns = {"1"};
  const ChamberLog log = read_chamber_log(path, spec);
  ASSERT_EQ(log.rows(), 4u);
  EXPECT_DOUBLE_EQ(log.time[3], 3.0 / 50.0);
}

TEST(ChamberLog, GyroUnitsBecomeDegreesPerHour) {
  TempDir dir;
  const auto path = dir.write("log.csv", kHeader + "0,20,1\n1,20,-0.5\n");
  LogSpec spec = named_spec();
  spec.gyro_unit = GyroUnit::dph;
  EXPECT_EQ(read_chamber_log(path, spec).gyro[0], (std::vector<double>{1, -0.5}));
  spec.gyro_unit = GyroUnit::dps;
  EXPECT_EQ(read_chamber_log(path, spec).gyro[0], (std::vector<double>{3600, -1800}));
  spec.gyro_unit = GyroUnit::radps;
  const auto radps = read_chamber_log(path, spec).gyro[0];
  EXPECT_NEAR(radps[0], 3600.0 * 180.0 / std::numbers::pi, 1e-6);
  EXPECT_NEAR(radps[0], 206264.806247, 1e-5);  // °/h in one rad/s
  EXPECT_NEAR(radps[1], -0.5 * 206264.806247, 1e-5);
  EXPECT_EQ(parse_gyro_unit("dps"), GyroUnit::dps);
  EXPECT_THROW(parse_gyro_unit("deg/s"), UsageError);
}

// --- every data error with its line and column ---

TEST(ChamberLogErrors, NonNumericCellInASmallFile) {
  TempDir dir;
  const auto path = dir.write("bad.csv", kHeader + "0,20,1\n1,20,x1.5\n2,20,1\n");
  const auto error = log_error(path, named_spec());
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 3u);
  EXPECT_EQ(error.file(), path);
  EXPECT_TRUE(contains(error.what(), "bad.csv:3:3: 'x1.5' is not a number")) << error.what();
}

TEST(ChamberLogErrors, NonNumericCellInStrictModeEvenInALongFile) {
  TempDir dir;
  std::string text = kHeader;
  for (int i = 0; i < 3000; ++i) text += std::to_string(i) + (i == 2000 ? ",2O,1\n" : ",20,1\n");
  const auto path = dir.write("strict.csv", text);
  LogSpec spec = named_spec();
  spec.csv = CsvOptions{.garbled_per_thousand = 0};
  const auto error = log_error(path, spec);
  EXPECT_EQ(error.line(), 2002u);
  EXPECT_EQ(error.column(), 2u);
  EXPECT_TRUE(contains(error.message(), "'2O' is not a number")) << error.what();
  // The default tolerance drops the same row instead.
  EXPECT_EQ(read_chamber_log(path, named_spec()).rows(), 2999u);
}

TEST(ChamberLogErrors, EmptyCell) {
  TempDir dir;
  const auto path = dir.write("empty_cell.csv", kHeader + "0,20,1\n1,,1\n2,20,1\n");
  const auto error = log_error(path, named_spec());
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 2u);
  EXPECT_TRUE(contains(error.message(), "empty cell")) << error.what();
}

TEST(ChamberLogErrors, NaNIsAlwaysAnError) {
  TempDir dir;
  std::string text = kHeader;
  for (int i = 0; i < 3000; ++i) text += std::to_string(i) + (i == 10 ? ",20,NaN\n" : ",20,1\n");
  const auto error = log_error(dir.write("nan.csv", text), named_spec());
  EXPECT_EQ(error.line(), 12u);
  EXPECT_EQ(error.column(), 3u);
  EXPECT_TRUE(contains(error.message(), "not a finite number")) << error.what();
}

TEST(ChamberLogErrors, InfIsAlwaysAnError) {
  TempDir dir;
  std::string text = kHeader;
  for (int i = 0; i < 3000; ++i) text += std::to_string(i) + (i == 2500 ? ",-inf,1\n" : ",20,1\n");
  const auto error = log_error(dir.write("inf.csv", text), named_spec());
  EXPECT_EQ(error.line(), 2502u);
  EXPECT_EQ(error.column(), 2u);
  EXPECT_TRUE(contains(error.message(), "'-inf' is not a finite number")) << error.what();
}

TEST(ChamberLogErrors, NumberOutOfRangeIsAnError) {
  TempDir dir;
  const auto error = log_error(dir.write("huge.csv", kHeader + "0,20,1\n1,20,1e999\n"), named_spec());
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 3u);
}

// A finite but absurd value is a wrong file, unit or scale, never a glitch to drop: an
// error at its cell like NaN, judged on the value after the unit and the scaling.
TEST(ChamberLogErrors, ValuesBeyondThePhysicalRangeAreErrors) {
  TempDir dir;
  std::string gyro = kHeader, temperature = kHeader;
  for (int i = 0; i < 3000; ++i) {
    gyro += std::to_string(i) + (i == 7 ? ",20,1e300\n" : ",20,1\n");
    temperature += std::to_string(i) + (i == 2000 ? ",-1e300,1\n" : ",20,1\n");
  }
  const auto gyro_error = log_error(dir.write("gyro.csv", gyro), named_spec());
  EXPECT_EQ(gyro_error.line(), 9u);
  EXPECT_EQ(gyro_error.column(), 3u);
  EXPECT_TRUE(contains(gyro_error.message(), "gyro '1e300' is 1e+300 °/h, beyond the physical range"))
      << gyro_error.what();
  const auto temperature_error = log_error(dir.write("temperature.csv", temperature), named_spec());
  EXPECT_EQ(temperature_error.line(), 2002u);
  EXPECT_EQ(temperature_error.column(), 2u);
  EXPECT_TRUE(contains(temperature_error.message(), "beyond the physical range of -273.15 to 1000 °C"))
      << temperature_error.what();

  // 2·10^5 °/s, or in rad/s: beyond.
  const auto fast = dir.write("fast.csv", kHeader + "0,20,1\n1,20,2e5\n");
  LogSpec spec = named_spec();
  spec.gyro_unit = GyroUnit::dps;
  EXPECT_EQ(log_error(fast, spec).line(), 3u);
  spec.gyro_unit = GyroUnit::radps;
  EXPECT_EQ(log_error(dir.write("fast_rad.csv", kHeader + "0,20,1\n1,20,2000\n"), spec).line(), 3u);
  // A raw-count log is judged after its scale: 16-bit counts of 1/256 °C above -231 °C
  // and a 32-bit gyro count at 1e-9 °/s per count load; without the scale they do not.
  const auto raw = dir.write("raw.csv", kHeader + "0,65535,2000000000\n1,32768,-2000000000\n");
  spec = named_spec();
  spec.gyro_unit = GyroUnit::dps;
  spec.scaling.temperature_scale = {0.00390625};
  spec.scaling.temperature_offset = {-231};
  spec.scaling.gyro_scale = {1e-9};
  const auto log = read_chamber_log(raw, spec);
  EXPECT_DOUBLE_EQ(log.temperature[0][0], 65535 * 0.00390625 - 231);
  EXPECT_DOUBLE_EQ(log.gyro[0][1], -2 * 3600.0);
  spec.scaling = {};
  const auto unscaled = log_error(raw, spec);
  EXPECT_EQ(unscaled.column(), 3u);
  EXPECT_TRUE(contains(unscaled.message(), "check --gyro-unit and --gyro-scale")) << unscaled.what();
  spec.scaling.gyro_scale = {1e-9};
  const auto unscaled_temperature = log_error(raw, spec);
  EXPECT_EQ(unscaled_temperature.column(), 2u);
  EXPECT_TRUE(contains(unscaled_temperature.message(), "check --temp-scale and --temp-offset"))
      << unscaled_temperature.what();
}

TEST(ChamberLogErrors, TimeGoingBackwards) {
  TempDir dir;
  std::string text = kHeader;
  for (int i = 0; i < 3000; ++i) text += std::to_string(i == 1200 ? 1100 : i) + ",20,1\n";
  const auto error = log_error(dir.write("back.csv", text), named_spec());
  EXPECT_EQ(error.line(), 1202u);
  EXPECT_EQ(error.column(), 1u);
  EXPECT_TRUE(contains(error.message(), "time goes backwards (1100 after 1199)")) << error.what();
  EXPECT_TRUE(contains(error.what(), "back.csv:1202:1: ")) << error.what();
}

TEST(ChamberLogErrors, TimeRepeated) {
  TempDir dir;
  const auto path = dir.write("repeat.csv", "temp,gyro_x,time_s\n20,1,0\n20,1,1\n20,1,1\n20,1,2\n");
  const auto error = log_error(path, named_spec());
  EXPECT_EQ(error.line(), 4u);
  EXPECT_EQ(error.column(), 3u);
  EXPECT_TRUE(contains(error.message(), "repeats")) << error.what();
}

TEST(ChamberLogErrors, ShortRowInsideTheData) {
  TempDir dir;
  const auto error = log_error(dir.write("short.csv", kHeader + "0,20,1\n1,20\n2,20,1\n3,20,1\n"), named_spec());
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 3u);
  EXPECT_TRUE(contains(error.message(), "row has 2 fields, expected 3")) << error.what();
}

TEST(ChamberLogErrors, LongRowInsideTheData) {
  TempDir dir;
  const auto error = log_error(dir.write("long.csv", kHeader + "0,20,1\n1,20,1,5\n2,20,1\n"), named_spec());
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 4u);
}

TEST(ChamberLogErrors, EmptyFileAndOnlyHeader) {
  TempDir dir;
  const auto empty = log_error(dir.write("empty.csv", ""), named_spec());
  EXPECT_EQ(empty.line(), 0u);
  EXPECT_TRUE(contains(empty.message(), "no data rows"));
  const auto header = log_error(dir.write("header.csv", kHeader), named_spec());
  EXPECT_EQ(header.line(), 1u);
  EXPECT_EQ(header.column(), 0u);
  EXPECT_TRUE(contains(header.message(), "only a header"));
}

TEST(ChamberLogErrors, MissingColumnNameNamesTheHeaderLine) {
  TempDir dir;
  const auto path = dir.write("log.csv", "# banner\n" + kHeader + "0,20,1\n");
  LogSpec spec = named_spec();
  spec.gyro_columns = {"gyro_q"};
  const auto error = log_error(path, spec);
  EXPECT_EQ(error.line(), 2u);
  EXPECT_EQ(error.column(), 0u);
  EXPECT_TRUE(contains(error.message(), "no gyro column named 'gyro_q'")) << error.what();
  EXPECT_TRUE(contains(error.message(), "time_s, temp, gyro_x")) << error.what();

  spec = named_spec();
  spec.time_column = "seconds";
  EXPECT_TRUE(contains(log_error(path, spec).message(), "no time column named 'seconds'"));
}

// A header naming a column twice: found by that name (given, or by the gyro/temp/time
// prefixes), either could be meant. Fuzzing found gyro_x twice fitted as two axes reading
// one column, in a model evaluate then refused.
TEST(ChamberLogErrors, AColumnNamedTwiceInTheHeader) {
  TempDir dir;
  const auto path = dir.write("log.csv", "# banner\ntime_s,temp,gyro_x,gyro_x,gyro_z\n0,20,1,2,3\n1,20,1,2,3\n");
  LogSpec detected;  // columns found by their names' prefixes
  auto error = log_error(path, detected);
  EXPECT_EQ(error.line(), 2u);
  EXPECT_EQ(error.column(), 4u);
  EXPECT_EQ(error.message(), "the header names 'gyro_x' twice (columns 3 and 4): the gyro column of that name is "
                             "ambiguous; rename one");
  error = log_error(path, named_spec());
  EXPECT_TRUE(contains(error.message(), "the header names 'gyro_x' twice (columns 3 and 4)")) << error.what();
  for (const auto& [header, said] :
       {std::pair{"time_s,temp,temp,gyro_x", "'temp' twice (columns 2 and 3): the temperature column"},
        std::pair{"time_s,time_s,temp,gyro_x", "'time_s' twice (columns 1 and 2): the time column"}}) {
    const auto twice = log_error(dir.write("twice.csv", std::string(header) + "\n0,0,20,1\n1,1,20,1\n"), detected);
    EXPECT_TRUE(contains(twice.message(), said)) << twice.what();
  }
  // By index the column is not in doubt; a repeated name nothing reads is no concern.
  LogSpec by_index = named_spec();
  by_index.gyro_columns = {"4", "5"};
  EXPECT_EQ(read_chamber_log(path, by_index).axes(), 2u);
  // Two axes chosen by index under one name: the model and the compensated columns know
  // the axes by name, so they would be one axis twice.
  by_index.gyro_columns = {"3", "4"};
  error = log_error(path, by_index);
  EXPECT_EQ(error.line(), 2u);
  EXPECT_EQ(error.column(), 4u);
  EXPECT_TRUE(contains(error.message(), "gyro columns 3 and 4 are both named 'gyro_x'")) << error.what();
  LogSpec temperatures = named_spec();
  temperatures.temperature_columns = {"2", "4"};
  const auto two_temps = dir.write("temps.csv", "time_s,temp,gyro_x,temp\n0,20,1,21\n1,20,1,21\n");
  EXPECT_TRUE(contains(log_error(two_temps, temperatures).message(), "temperature columns 2 and 4 are both named 'temp'"));
  const auto unused = dir.write("unused.csv", "time_s,temp,gyro_x,note,note\n0,20,1,5,6\n1,20,1,5,6\n");
  EXPECT_EQ(read_chamber_log(unused, detected).axes(), 1u);
}

TEST(ChamberLogErrors, ColumnIndexOutOfRange) {
  TempDir dir;
  const auto with_header = dir.write("h.csv", kHeader + "0,20,1\n");
  LogSpec spec = named_spec();
  spec.temperature_columns = {"4"};
  auto error = log_error(with_header, spec);
  EXPECT_EQ(error.line(), 1u);
  EXPECT_EQ(error.column(), 0u);
  EXPECT_TRUE(contains(error.message(), "temperature column 4 is out of range: the file has 3 columns"))
      << error.what();

  const auto without_header = dir.write("n.csv", "0,20,1\n1,20,1\n");
  spec.time_column = "1";
  spec.gyro_columns = {"0"};
  spec.temperature_columns = {"2"};
  error = log_error(without_header, spec);
  EXPECT_EQ(error.line(), 0u);
  EXPECT_TRUE(contains(error.message(), "gyro column 0 is out of range")) << error.what();
}

TEST(ChamberLogErrors, NameWithoutHeaderRow) {
  TempDir dir;
  const auto error = log_error(dir.write("n.csv", "0,20,1\n1,20,1\n"), named_spec());
  EXPECT_TRUE(contains(error.message(), "no header row")) << error.what();
}

TEST(ChamberLog, RareGarbledRowInALongLogIsDroppedAndItsNeighboursKept) {
  TempDir dir;
  std::string text = kHeader;
  for (int i = 0; i < 2000; ++i) text += std::to_string(i) + (i == 1234 ? ",20,-0.3-0.31\n" : ",20,1\n");
  const auto path = dir.write("rare.csv", text);
  const ChamberLog log = read_chamber_log(path, named_spec());
  ASSERT_EQ(log.rows(), 1999u);
  EXPECT_EQ(log.time[1233], 1233);
  EXPECT_EQ(log.time[1234], 1235);
  EXPECT_EQ(log.line[1233], 1235u);
  EXPECT_EQ(log.line[1234], 1237u);
  ASSERT_EQ(log.warnings.size(), 1u);
  EXPECT_TRUE(contains(log.warnings[0], "rare.csv:1236:3: '-0.3-0.31' is not a number; garbled row dropped"))
      << log.warnings[0];
}

// --- the real BMI270 logs ---

LogSpec bmi270_spec() {
  LogSpec spec;
  spec.rate_hz = 50;
  spec.temperature_columns = {"1"};
  spec.gyro_columns = {"5", "6", "7"};
  spec.gyro_unit = GyroUnit::dps;
  return spec;
}

std::string bmi270(const std::string& name) { return testing::shared_data("real/bmi270/" + name); }

bool any_warning(const ChamberLog& log, const std::string& part) {
  for (const auto& warning : log.warnings) {
    if (contains(warning, part)) return true;
  }
  return false;
}

TEST(Bmi270, ColdLogLoadsWithBannerGarbledRowAndCutShortLastRow) {
  THERMODRIFT_SKIP_WITHOUT_SHARED_DATA("real/bmi270");
  const ChamberLog log = read_chamber_log(bmi270("cold.csv"), bmi270_spec());
  // 3258 lines: banner, 3255 rows, "-0.3-0.31" on line 9, a lone "1" at the end.
  EXPECT_EQ(log.rows(), 3255u);
  EXPECT_EQ(log.axes(), 3u);
  EXPECT_EQ(log.line.front(), 2u);
  EXPECT_DOUBLE_EQ(log.time[1], 0.02);
  EXPECT_DOUBLE_EQ(log.temperature[0][0], 13.255859);
  EXPECT_DOUBLE_EQ(log.gyro[0][0], -0.12 * 3600);  // first row, column 5, °/s -> °/h
  EXPECT_TRUE(any_warning(log, "skipped 1 banner/comment line")) << ::testing::PrintToString(log.warnings);
  EXPECT_TRUE(any_warning(log, "cold.csv:9:6: '-0.3-0.31' is not a number; garbled row dropped"))
      << ::testing::PrintToString(log.warnings);
  EXPECT_TRUE(any_warning(log, "line 3258: last row cut short (1 of 7 fields)"))
      << ::testing::PrintToString(log.warnings);
  for (double t : log.temperature[0]) {
    ASSERT_GT(t, 12.5);
    ASSERT_LT(t, 13.8);
  }
}

TEST(Bmi270, HotLogLoadsWithBannerCutShortFirstAndLastRowsAndAGarbledRow) {
  THERMODRIFT_SKIP_WITHOUT_SHARED_DATA("real/bmi270");
  const ChamberLog log = read_chamber_log(bmi270("hot.csv"), bmi270_spec());
  // 6537 lines: banner, a 6-field first row, an 8-field row on line 13, a lone "4" at the end.
  EXPECT_EQ(log.rows(), 6533u);
  EXPECT_EQ(log.line.front(), 3u);
  EXPECT_DOUBLE_EQ(log.temperature[0][0], 49.353516);
  EXPECT_TRUE(any_warning(log, "skipped 1 banner/comment line")) << ::testing::PrintToString(log.warnings);
  EXPECT_TRUE(any_warning(log, "line 2: first row cut short (6 of 7 fields), dropped"))
      << ::testing::PrintToString(log.warnings);
  EXPECT_TRUE(any_warning(log, "hot.csv:13:8: row has 8 fields, expected 7; garbled row dropped"))
      << ::testing::PrintToString(log.warnings);
  EXPECT_TRUE(any_warning(log, "line 6537: last row cut short (1 of 7 fields)"))
      << ::testing::PrintToString(log.warnings);
  EXPECT_NEAR(log.time.back(), 6532 / 50.0, 1e-9);
  for (double t : log.temperature[0]) {
    ASSERT_GT(t, 46.5);
    ASSERT_LT(t, 50.0);
  }
}

TEST(Bmi270, StrictReadingRefusesTheGarbledRow) {
  THERMODRIFT_SKIP_WITHOUT_SHARED_DATA("real/bmi270");
  LogSpec spec = bmi270_spec();
  spec.csv.garbled_per_thousand = 0;
  const auto error = log_error(bmi270("cold.csv"), spec);
  EXPECT_EQ(error.line(), 9u);
  EXPECT_EQ(error.column(), 6u);
}

TEST(SliceRows, KeepsTheRowsAsked) {
  TempDir dir;
  const auto log = read_chamber_log(dir.write("log.csv", kHeader + "0,20,1\n1,21,2\n2,22,3\n3,23,4\n"), named_spec());
  const auto part = slice_rows(log, 1, 3);
  EXPECT_EQ(part.time, (std::vector<double>{1, 2}));
  EXPECT_EQ(part.gyro[0], (std::vector<double>{2, 3}));
  EXPECT_EQ(part.temperature[0], (std::vector<double>{21, 22}));
  EXPECT_EQ(part.line, (std::vector<std::size_t>{3, 4}));
}

// A log cut mid-ramp: the history before it continues each thermometer's initial line
// (exactly, for a line), held within the thermometer's range over the log, at the log's
// step; the gyro columns hold their first value, and the log's rows follow unchanged.
TEST(ChamberLog, RampHistoryContinuesEachThermometersInitialLineWithinItsRange) {
  ChamberLog log;
  log.source = "cut.csv";
  log.gyro_names = {"gyro_x"};
  log.temperature_names = {"temp_a", "temp_b"};
  log.gyro.resize(1), log.temperature.resize(2);
  for (int i = 0; i < 1000; ++i) {
    const double t = 100.0 + 2.0 * i;
    log.time.push_back(t);
    log.line.push_back(static_cast<std::size_t>(i) + 2);
    log.gyro[0].push_back(0.5 + 0.001 * i);
    const double u = t - 100.0;
    // up 0.6 °C/min, then down to 10.04 °C
    log.temperature[0].push_back(u <= 1000 ? 20.0 + 0.01 * u : 30.0 - 0.02 * (u - 1000));
    log.temperature[1].push_back(5.0 - 0.005 * std::min(u, 600.0));  // down, then flat at 2 °C
  }
  const ChamberLog history = with_ramp_history(log, 3600, 300);
  const std::size_t count = 1800;  // 3600 s at the log's 2 s step
  ASSERT_EQ(history.rows(), count + log.rows());
  EXPECT_EQ(history.time[count - 1], 98.0);
  EXPECT_EQ(history.time[0], 100.0 - 3600.0);
  for (std::size_t k = 0; k < count; ++k) {
    const double before = history.time[k] - 100.0;  // < 0
    // held at the log's lowest, and the other at its highest
    EXPECT_NEAR(history.temperature[0][k], std::max(20.0 + 0.01 * before, 10.04), 1e-9) << k;
    EXPECT_NEAR(history.temperature[1][k], std::min(5.0 - 0.005 * before, 5.0), 1e-9) << k;
    EXPECT_EQ(history.gyro[0][k], 0.5);
    EXPECT_EQ(history.line[k], 0u);
  }
  EXPECT_NEAR(history.temperature[0][count - 1], 19.98, 1e-9);
  EXPECT_NEAR(history.temperature[0][0], 10.04, 1e-9);
  for (std::size_t i = 0; i < log.rows(); ++i) {
    EXPECT_EQ(history.time[count + i], log.time[i]);
    EXPECT_EQ(history.gyro[0][count + i], log.gyro[0][i]);
    EXPECT_EQ(history.temperature[1][count + i], log.temperature[1][i]);
    EXPECT_EQ(history.line[count + i], log.line[i]);
  }
}

}  // namespace
}  // namespace thermodrift
