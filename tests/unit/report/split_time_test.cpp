// report --split-time: the row a time names, on logs with seconds, epoch and ISO 8601
// clocks and on logs without a time column.
#include <gtest/gtest.h>

#include <string>

#include "thermodrift/error.hpp"
#include "thermodrift/io/time_stamp.hpp"
#include "thermodrift/report/study.hpp"

namespace thermodrift {
namespace {

// Rows every 10 s from the origin written as `first_cell` (none: a log read with --rate).
ChamberLog log_from(const std::optional<std::string>& first_cell, TimeUnit unit = TimeUnit::s) {
  ChamberLog log;
  for (int k = 0; k < 100; ++k) log.time.push_back(10.0 * k);
  if (first_cell) {
    TimeOrigin origin{*first_cell, unit, {}};
    std::string problem;
    EXPECT_TRUE(parse_time_stamp(*first_cell, unit, origin.stamp, &problem)) << problem;
    log.time_origin = origin;
  }
  return log;
}

TEST(SplitTime, SecondsOnTheLogsOwnClock) {
  EXPECT_EQ(row_at_time(log_from("0"), "500"), 50u);
  EXPECT_EQ(row_at_time(log_from("0"), "505"), 51u);  // the first row at or after the time
  EXPECT_EQ(row_at_time(log_from("1000"), "1500"), 50u);
  EXPECT_EQ(row_at_time(log_from(std::nullopt), "500"), 50u);  // --rate: from the first row
  EXPECT_EQ(row_at_time(log_from("0"), "-5"), 0u);
  EXPECT_EQ(row_at_time(log_from("0"), "1e6"), 100u);  // after the log: nothing held out
}

// An epoch in ns: the time is still given in s, and the split is exact to the last digit.
TEST(SplitTime, EpochClocksKeepTheirLastDigit) {
  const ChamberLog log = log_from("1772898300123456789", TimeUnit::ns);
  EXPECT_EQ(row_at_time(log, "1772898800.123456789"), 50u);
  EXPECT_EQ(row_at_time(log, "1772898800.12345679"), 51u);
}

// ISO-stamped logs: a stamp names the instant; a number stays on the log's clock (s since
// 1970), as for any other time column.
TEST(SplitTime, IsoStampsNameTheInstant) {
  const ChamberLog log = log_from("2026-03-07T12:00:00Z");
  EXPECT_EQ(row_at_time(log, "2026-03-07T12:08:20Z"), 50u);
  EXPECT_EQ(row_at_time(log, "2026-03-07T13:08:20+01:00"), 50u);
  EXPECT_EQ(row_at_time(log, "2026-03-07 12:08:20"), 50u);
  const TimeStamp origin = log.time_origin->stamp;
  EXPECT_EQ(row_at_time(log, std::to_string(origin.seconds + 500)), 50u);
}

TEST(SplitTime, WhatIsNotATimeIsAUsageError) {
  EXPECT_THROW(row_at_time(log_from("0"), "nan"), UsageError);
  EXPECT_THROW(row_at_time(log_from("0"), "soon"), UsageError);
  EXPECT_THROW(row_at_time(log_from("0"), ""), UsageError);
  try {
    row_at_time(log_from(std::nullopt), "2026-03-07T12:08:20Z");
    FAIL() << "a stamp for a log without a time column was taken";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("no time column"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace thermodrift
