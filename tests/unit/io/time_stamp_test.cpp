// Time cells read exactly: numbers in each unit, every ISO 8601 form the bench writes,
// and what is said of a malformed one.
#include "thermodrift/io/time_stamp.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

TimeStamp read(std::string_view cell, TimeUnit unit = TimeUnit::s) {
  TimeStamp stamp;
  std::string problem;
  EXPECT_TRUE(parse_time_stamp(cell, unit, stamp, &problem)) << cell << ": " << problem;
  return stamp;
}

std::string problem_of(std::string_view cell, TimeUnit unit = TimeUnit::s) {
  TimeStamp stamp;
  std::string problem;
  EXPECT_FALSE(parse_time_stamp(cell, unit, stamp, &problem)) << cell << " was read";
  return problem;
}

// Seconds since 1970 of a civil date and time, by the standard library's calendar.
std::int64_t epoch_seconds(int year, unsigned month, unsigned day, int hour, int minute, int second) {
  using namespace std::chrono;
  const sys_days date = year_month_day{std::chrono::year{year}, std::chrono::month{month}, std::chrono::day{day}};
  return date.time_since_epoch().count() * 86400 + hour * 3600 + minute * 60 + second;
}

TEST(TimeUnit, NamesAndExponents) {
  for (const auto* name : {"s", "ms", "us", "ns"}) EXPECT_EQ(to_string(parse_time_unit(name)), name);
  EXPECT_EQ(decimal_exponent(TimeUnit::s), 0);
  EXPECT_EQ(decimal_exponent(TimeUnit::ms), -3);
  EXPECT_EQ(decimal_exponent(TimeUnit::us), -6);
  EXPECT_EQ(decimal_exponent(TimeUnit::ns), -9);
  EXPECT_THROW(parse_time_unit("min"), UsageError);
}

// The same instant, 12.5 s, written in each unit.
TEST(TimeStamp, EachUnitReadsTheSameInstant) {
  const TimeStamp expected{12, 500'000'000'000'000'000, false};
  EXPECT_EQ(read("12.5", TimeUnit::s), expected);
  EXPECT_EQ(read("12500", TimeUnit::ms), expected);
  EXPECT_EQ(read("12500000", TimeUnit::us), expected);
  EXPECT_EQ(read("12500000000", TimeUnit::ns), expected);
  EXPECT_EQ(read("1.25e4", TimeUnit::ms), expected);
  EXPECT_EQ(read("+1250E-2", TimeUnit::s), expected);
  EXPECT_EQ(read("0.0125", TimeUnit::ms), (TimeStamp{0, 12'500'000'000'000, false}));
}

TEST(TimeStamp, NegativeTimesKeepAPositiveFraction) {
  const TimeStamp stamp = read("-1.25");
  EXPECT_EQ(stamp.seconds, -2);
  EXPECT_EQ(stamp.attoseconds, 750'000'000'000'000'000);
  EXPECT_EQ(stamp.approximate_seconds(), -1.25);
  EXPECT_EQ(read("-0"), TimeStamp{});
}

// A Unix epoch in ns has 19 digits; a double holds 15-17. The difference to a first
// stamp must keep every ns.
TEST(TimeStamp, EpochDifferencesKeepTheLastDigit) {
  const TimeStamp first = read("1772898300123456789", TimeUnit::ns);
  const TimeStamp next = read("1772898300123456790", TimeUnit::ns);
  EXPECT_EQ(first.seconds, 1772898300);
  EXPECT_EQ(first.attoseconds, 123'456'789'000'000'000);
  EXPECT_EQ(next.seconds_since(first), 1e-9);
  const TimeStamp micro = read("1772898300.123456");
  const TimeStamp later = read("1772898301.123457");
  EXPECT_DOUBLE_EQ(later.seconds_since(micro), 1.000001);
  // As doubles the two epochs are the same number: the exact read is what tells them apart.
  EXPECT_EQ(1772898300123456789.0, 1772898300123456790.0);
}

TEST(TimeStamp, NumbersThatAreNotTimes) {
  EXPECT_NE(problem_of("abc").find("'abc' is not a number"), std::string::npos);
  EXPECT_NE(problem_of("1.2.3").find("is not a number"), std::string::npos);
  EXPECT_NE(problem_of("-0.3-0.31").find("is not a number"), std::string::npos);
  EXPECT_NE(problem_of("").find("empty cell"), std::string::npos);
  EXPECT_NE(problem_of("1e30").find("out of the range"), std::string::npos);
}

// Long fuzzing found "2026E-2435010336759301097": the reader built a string of 2.4e18
// zeros for the fraction. Exponents that no line's digits can reach are settled first:
// below an attosecond is 0, above the range an error, and neither allocates.
TEST(TimeStamp, HugeExponentsAreSettledWithoutBuildingTheDigits) {
  EXPECT_EQ(read("2026E-2435010336759301097"), TimeStamp{});
  EXPECT_EQ(read("-7e-9223372036854775807"), TimeStamp{});
  EXPECT_EQ(read("1e-19"), TimeStamp{});
  EXPECT_EQ(read("1e-18").attoseconds, 1);
  EXPECT_EQ(read("123456e-23").attoseconds, 1);
  EXPECT_EQ(read("5e-3", TimeUnit::ns).attoseconds, 5'000'000);  // 5e-12 s
  EXPECT_NE(problem_of("1e9223372036854775807").find("out of the range"), std::string::npos);
  EXPECT_NE(problem_of("1e2000000000").find("out of the range"), std::string::npos);
  EXPECT_NE(problem_of("1e99999999999999999999").find("out of the range"), std::string::npos);
}

TEST(DaysFromCivil, AgreesWithTheStandardCalendar) {
  for (const auto& [year, month, day] : {std::tuple{1970, 1u, 1u}, {2000, 2u, 29u}, {2026, 3u, 7u}, {1969, 12u, 31u},
                                         {2100, 3u, 1u}, {1600, 1u, 1u}}) {
    EXPECT_EQ(days_from_civil(year, month, day) * 86400, epoch_seconds(year, month, day, 0, 0, 0))
        << year << "-" << month << "-" << day;
  }
}

TEST(Iso8601, UtcWithAMillisecondFraction) {
  const TimeStamp stamp = read("2026-03-07T15:45:00.123Z");
  EXPECT_TRUE(stamp.iso);
  EXPECT_EQ(stamp.seconds, epoch_seconds(2026, 3, 7, 15, 45, 0));
  EXPECT_EQ(stamp.attoseconds, 123'000'000'000'000'000);
}

TEST(Iso8601, OffsetsWithAndWithoutColonGiveTheSameInstant) {
  const TimeStamp utc = read("2026-03-07T15:45:00Z");
  EXPECT_EQ(read("2026-03-07T16:45:00+01:00"), utc);
  EXPECT_EQ(read("2026-03-07T16:45:00+0100"), utc);
  EXPECT_EQ(read("2026-03-07T10:15:00-0530"), utc);
  EXPECT_EQ(read("2026-03-07T10:15:00-05:30"), utc);
  EXPECT_EQ(read("2026-03-08T00:45:00+09"), utc);
}

TEST(Iso8601, NoFractionLongFractionAndASpaceForTheT) {
  EXPECT_EQ(read("2026-03-07 15:45:00Z"), read("2026-03-07T15:45:00Z"));
  EXPECT_EQ(read("2026-03-07T15:45:00Z").attoseconds, 0);
  const TimeStamp fine = read("2026-03-07T15:45:00.123456789012345678901Z");
  EXPECT_EQ(fine.attoseconds, 123'456'789'012'345'678);  // cut at 10^-18 s
  EXPECT_EQ(read("2026-03-07T15:45:00,5Z").attoseconds, 500'000'000'000'000'000);
  // A unit does not apply to a date.
  EXPECT_EQ(read("2026-03-07T15:45:00Z", TimeUnit::ns), read("2026-03-07T15:45:00Z"));
}

TEST(Iso8601, WithoutAZoneTheWallClockIsReadAsUtc) {
  // Loggers often write local time without a zone: differences between rows stay exact.
  EXPECT_EQ(read("2026-03-07T15:45:00.25"), read("2026-03-07T15:45:00.25Z"));
  EXPECT_EQ(read("2026-03-07 15:45:01").seconds_since(read("2026-03-07 15:44:59.5")), 1.5);
}

TEST(Iso8601, LeapDayAndTheTurnOfTheYear) {
  EXPECT_EQ(read("2028-03-01T00:00:00Z").seconds - read("2028-02-28T00:00:00Z").seconds, 2 * 86400);
  EXPECT_EQ(read("2027-01-01T00:00:00Z").seconds - read("2026-12-31T23:59:59Z").seconds, 1);
}

TEST(Iso8601, MalformedStampsSayWhatWasExpectedWhere) {
  struct Case {
    const char* cell;
    const char* expected;
  };
  for (const auto& [cell, expected] : {
           Case{"2026-03-07T15:4:00Z", "expected two-digit minutes (00-59) at character 15"},
           Case{"2026-13-07T15:45:00Z", "expected a two-digit month at character 6"},
           Case{"2026-02-30T15:45:00Z", "expected a day of 2026-02 (01-28) at character 9"},
           Case{"2026-03-07X15:45:00Z", "expected 'T' or a space between date and time at character 11"},
           Case{"2026-03-07T25:45:00Z", "expected two-digit hours (00-23) at character 12"},
           Case{"2026-03-07T15:45:00 ", "expected a fraction, 'Z' or a UTC offset (+hh:mm) after the seconds at character 20"},
           Case{"2026-03-07T15:45:00.Z", "expected digits of a fraction of a second at character 21"},
           Case{"2026-03-07T15:45:00+1:00", "expected two-digit hours of the UTC offset (00-23) at character 21"},
           Case{"2026-03-07T15:45:00Zjunk", "expected the end of the time stamp at character 21"},
           Case{"2026-03-07", "expected 'T' or a space between date and time at character 11"},
       }) {
    const std::string problem = problem_of(cell);
    EXPECT_NE(problem.find(std::string("'") + cell + "' is not an ISO 8601 time stamp"), std::string::npos) << problem;
    EXPECT_NE(problem.find(expected), std::string::npos) << problem;
  }
}

}  // namespace
}  // namespace thermodrift
