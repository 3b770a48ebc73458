// Time stamps as chamber logs write them: a number in s, ms, µs or ns (a Unix epoch as
// often as not), or an ISO 8601 date and time. Read exactly, as integers, so that a
// 19-digit epoch in ns or an epoch in s with a microsecond fraction keeps its last
// digit: a log's times are differences taken in integers before one rounding to double.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace thermodrift {

enum class TimeUnit { s, ms, us, ns };

TimeUnit parse_time_unit(std::string_view name);  // "s", "ms", "us", "ns"; UsageError otherwise
std::string_view to_string(TimeUnit unit);
int decimal_exponent(TimeUnit unit);  // one unit = 10^exponent s: 0, -3, -6, -9

// An instant read exactly: seconds + attoseconds / 10^18, 0 <= attoseconds < 10^18
// (negative times have negative seconds). Digits beyond 10^-18 s are cut off.
struct TimeStamp {
  std::int64_t seconds = 0;
  std::int64_t attoseconds = 0;
  bool iso = false;  // read from an ISO 8601 date and time (seconds since 1970 UTC)

  // (*this - origin) in seconds: the difference in integers, then one rounding to double.
  double seconds_since(const TimeStamp& origin) const;
  // The stamp in seconds, rounded to double (loses sub-µs digits of an epoch).
  double approximate_seconds() const;
  auto operator<=>(const TimeStamp& other) const {
    if (seconds != other.seconds) return seconds <=> other.seconds;
    return attoseconds <=> other.attoseconds;
  }
  bool operator==(const TimeStamp& other) const { return seconds == other.seconds && attoseconds == other.attoseconds; }
};

// True when `cell` is meant as an ISO 8601 date (it starts "YYYY-"), so that a malformed
// one is reported as a time stamp and not as a number.
bool looks_like_iso_8601(std::string_view cell);

// Reads one time cell: an ISO 8601 date and time ("2026-03-07T15:45:00.123Z", a space for
// the T, a fraction of any length, Z, an offset +01:00 / -0530, or no zone: read as UTC),
// else a decimal number (sign, fraction, exponent) in `unit`. Returns false with what was
// expected in *problem (one line, naming the cell) when the cell is neither.
bool parse_time_stamp(std::string_view cell, TimeUnit unit, TimeStamp& stamp, std::string* problem);

// Days from 1970-01-01 to the proleptic Gregorian date y-m-d (H. Hinnant's days_from_civil).
std::int64_t days_from_civil(std::int64_t year, unsigned month, unsigned day);

}  // namespace thermodrift
