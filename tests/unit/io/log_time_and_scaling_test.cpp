// Chamber logs as they come off the bench: time in ms, µs, ns or as ISO 8601 stamps,
// Unix epochs that must stay exact, raw counts scaled to °C and °/h; and the streaming
// reader agreeing with the whole-file one.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>

#include "../../support/temp_dir.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift {
namespace {

using testing::TempDir;

using testing::contains;

LogSpec spec_in(TimeUnit unit) {
  LogSpec spec;
  spec.time_column = "time";
  spec.time_unit = unit;
  return spec;
}

TEST(LogTime, EachUnitGivesSecondsFromTheFirstRow) {
  TempDir dir;
  struct Case {
    TimeUnit unit;
    const char* times[3];
  };
  for (const auto& [unit, times] : {Case{TimeUnit::s, {"100", "100.5", "102"}}, Case{TimeUnit::ms, {"100000", "100500", "102000"}},
                                    Case{TimeUnit::us, {"1e8", "100500000", "102000000"}},
                                    Case{TimeUnit::ns, {"100000000000", "100500000000", "102000000000"}}}) {
    const auto path = dir.write("log.csv", fmt::format("time,temp,gyro\n{},20,1\n{},21,2\n{},22,3\n", times[0], times[1], times[2]));
    const ChamberLog log = read_chamber_log(path, spec_in(unit));
    EXPECT_EQ(log.time, (std::vector<double>{0, 0.5, 2})) << to_string(unit);
    ASSERT_TRUE(log.time_origin);
    EXPECT_EQ(log.time_origin->text, times[0]);
    EXPECT_EQ(log.time_origin->unit, unit);
    EXPECT_EQ(log.time_origin->stamp.seconds, 100);
  }
}

// 1 ns steps on a 19-digit epoch: as doubles every row would read the same time.
TEST(LogTime, EpochInNanosecondsKeepsSubMicrosecondSteps) {
  TempDir dir;
  const auto path = dir.write("log.csv",
                              "time,temp,gyro\n1772898300123456789,20,1\n1772898300123456790,20,1\n"
                              "1772898300123457289,20,1\n1772898301123456789,20,1\n");
  const ChamberLog log = read_chamber_log(path, spec_in(TimeUnit::ns));
  ASSERT_EQ(log.rows(), 4u);
  EXPECT_EQ(log.time[0], 0.0);
  EXPECT_EQ(log.time[1], 1e-9);
  EXPECT_EQ(log.time[2], 500e-9);
  EXPECT_EQ(log.time[3], 1.0);
  EXPECT_EQ(log.time_origin->text, "1772898300123456789");
}

TEST(LogTime, EpochInSecondsWithAMicrosecondFraction) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time,temp,gyro\n1772898300.123456,20,1\n1772898300.123457,20,1\n");
  const ChamberLog log = read_chamber_log(path, spec_in(TimeUnit::s));
  EXPECT_DOUBLE_EQ(log.time[1], 1e-6);
  // The same stamps as doubles differ by a multiple of 2^-23 s, not by 1 µs.
  EXPECT_NE(1772898300.123457 - 1772898300.123456, 1e-6);
}

TEST(LogTime, IsoStampsInEveryFormAreSecondsFromTheFirst) {
  TempDir dir;
  const auto path = dir.write("log.csv",
                              "time;temp;gyro\n"
                              "2026-03-07T15:45:00Z;20;1\n"
                              "2026-03-07T15:45:00.25Z;20;1\n"
                              "2026-03-07 16:45:01+01:00;20;1\n"
                              "2026-03-07T10:15:01.5-0530;20;1\n"
                              "2026-03-07T15:45:02.000000001Z;20;1\n");
  const ChamberLog log = read_chamber_log(path, spec_in(TimeUnit::ms));  // the unit does not apply to dates
  const std::vector<double> expected{0, 0.25, 1, 1.5, 2.000000001};
  ASSERT_EQ(log.rows(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_DOUBLE_EQ(log.time[i], expected[i]) << i;
  EXPECT_EQ(log.time_origin->text, "2026-03-07T15:45:00Z");
  EXPECT_TRUE(log.time_origin->stamp.iso);
}

TEST(LogTime, MalformedIsoStampNamesFileLineColumnAndWhatWasExpected) {
  TempDir dir;
  const auto path = dir.write("log.csv", "temp,time,gyro\n20,2026-03-07T15:45:00Z,1\n20,2026-03-07T15:4:01Z,1\n");
  try {
    read_chamber_log(path, spec_in(TimeUnit::s));
    ADD_FAILURE() << "a malformed time stamp was read";
  } catch (const DataError& error) {
    EXPECT_EQ(error.line(), 3u);
    EXPECT_EQ(error.column(), 2u);
    EXPECT_TRUE(contains(error.what(), path + ":3:2: '2026-03-07T15:4:01Z' is not an ISO 8601 time stamp: expected "
                                              "two-digit minutes (00-59) at character 15"))
        << error.what();
  }
}

TEST(LogTime, ANumberAfterIsoStampsIsAnError) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time,temp,gyro\n2026-03-07T15:45:00Z,20,1\n17,20,1\n");
  try {
    read_chamber_log(path, spec_in(TimeUnit::s));
    ADD_FAILURE() << "a number was read after ISO stamps";
  } catch (const DataError& error) {
    EXPECT_EQ(error.line(), 3u);
    EXPECT_TRUE(contains(error.message(), "expected an ISO 8601 time stamp like the first row's")) << error.what();
  }
}

TEST(LogTime, OrderIsJudgedOnTheExactStamps) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time,temp,gyro\n1772898300123456790,20,1\n1772898300123456789,20,1\n");
  try {
    read_chamber_log(path, spec_in(TimeUnit::ns));
    ADD_FAILURE() << "time going back 1 ns was read";
  } catch (const DataError& error) {
    EXPECT_EQ(error.line(), 3u);
    EXPECT_EQ(error.column(), 1u);
    EXPECT_TRUE(contains(error.message(), "time goes backwards (1772898300123456789 after 1772898300123456790)"))
        << error.what();
  }
}

// Raw counts: °C = A·raw + B per temperature column, °/h = unit · K · raw per gyro column.
TEST(LogScaling, RawCountsBecomeDegreesAndDegreesPerHour) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time,temp_a,temp_b,gyro_x,gyro_y\n0,1000,2000,2,4\n1,1256,2256,-2,8\n");
  LogSpec spec;
  spec.gyro_unit = GyroUnit::dps;
  spec.scaling.temperature_scale = {0.00390625};
  spec.scaling.temperature_offset = {-231, -200};
  spec.scaling.gyro_scale = {0.5, 0.25};
  const ChamberLog log = read_chamber_log(path, spec);
  EXPECT_EQ(log.temperature[0], (std::vector<double>{1000 * 0.00390625 - 231, 1256 * 0.00390625 - 231}));
  EXPECT_EQ(log.temperature[1], (std::vector<double>{2000 * 0.00390625 - 200, 2256 * 0.00390625 - 200}));
  EXPECT_EQ(log.gyro[0], (std::vector<double>{3600, -3600}));
  EXPECT_EQ(log.gyro[1], (std::vector<double>{3600, 7200}));
  EXPECT_FALSE(spec.scaling.is_default());
  EXPECT_TRUE(LogScaling{}.is_default());
  EXPECT_TRUE((LogScaling{{1, 1}, {0}, {1}}).is_default());
}

TEST(LogScaling, ListsMustFitTheColumnsAndScalesMustBeFiniteAndNonZero) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time,temp_a,temp_b,gyro_x,gyro_y\n0,1,2,3,4\n1,1,2,3,4\n");
  LogSpec three;
  three.scaling.temperature_scale = {1, 2, 3};
  try {
    read_chamber_log(path, three);
    ADD_FAILURE() << "three scales for two temperature columns";
  } catch (const UsageError& error) {
    EXPECT_TRUE(contains(error.what(), "--temp-scale has 3 values for 2 temperature columns")) << error.what();
  }
  for (const LogScaling& bad : {LogScaling{{0}, {}, {}}, LogScaling{{}, {}, {0}}, LogScaling{{}, {NAN}, {}},
                                LogScaling{{INFINITY}, {}, {}}}) {
    LogSpec spec;
    spec.scaling = bad;
    EXPECT_THROW(read_chamber_log(path, spec), UsageError);
  }
}

// compensate streams through LogSampleReader; fit reads whole files: the same rows,
// times, values, origin.
TEST(LogSampleReader, AgreesWithTheWholeFileReader) {
  TempDir dir;
  std::string text = "# bench log\ntime,temp,gyro\n";
  for (int i = 0; i < 2000; ++i) {
    text += fmt::format("{},{},{}\n", 1772898300000000000LL + 333333333LL * i, 1000 + i % 17, i % 5 - 2);
    if (i == 700) text += fmt::format("{},-0.3-0.31,1\n", 1772898300000000000LL + 333333333LL * i + 1);  // garbled, dropped
  }
  const auto path = dir.write("log.csv", text);
  LogSpec spec = spec_in(TimeUnit::ns);
  spec.scaling.temperature_scale = {0.00390625};
  spec.scaling.temperature_offset = {-231};
  spec.gyro_unit = GyroUnit::radps;
  spec.scaling.gyro_scale = {0.5};
  const ChamberLog whole = read_chamber_log(path, spec);

  CsvReader reader(path, spec.csv);
  LogSampleReader samples(reader, spec);
  LogSample sample;
  std::size_t row = 0;
  while (auto csv_row = samples.next(sample)) {
    ASSERT_LT(row, whole.rows());
    EXPECT_EQ(csv_row->line, whole.line[row]);
    EXPECT_EQ(sample.time, whole.time[row]);
    EXPECT_EQ(sample.gyro[0], whole.gyro[0][row]);
    EXPECT_EQ(sample.temperature[0], whole.temperature[0][row]);
    ++row;
  }
  EXPECT_EQ(row, whole.rows());
  EXPECT_EQ(row, 2000u);
  EXPECT_EQ(samples.time_origin()->text, whole.time_origin->text);
  EXPECT_DOUBLE_EQ(whole.time[3], 0.999999999);
  EXPECT_DOUBLE_EQ(whole.gyro[0][0], -2 * 0.5 * 3600 * 180 / std::numbers::pi);
}

}  // namespace
}  // namespace thermodrift
