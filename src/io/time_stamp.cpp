#include "thermodrift/io/time_stamp.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace {

constexpr std::int64_t kAttoPerSecond = 1'000'000'000'000'000'000;
constexpr int kAttoDigits = 18;
// |t| below 10^17 s (3 billion years): the difference of two stamps fits in int64.
constexpr int kMaxIntegerDigits = 17;

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// -(seconds + atto/10^18) with 0 <= atto < 10^18 kept.
void negate(TimeStamp& stamp) {
  if (stamp.attoseconds == 0) {
    stamp.seconds = -stamp.seconds;
  } else {
    stamp.seconds = -stamp.seconds - 1;
    stamp.attoseconds = kAttoPerSecond - stamp.attoseconds;
  }
}

// The first 18 digits of a decimal fraction as attoseconds (shorter ones padded).
std::int64_t attoseconds_of(std::string_view fraction_digits) {
  std::int64_t atto = 0;
  for (int i = 0; i < kAttoDigits; ++i) {
    atto = atto * 10 + (i < static_cast<int>(fraction_digits.size()) ? fraction_digits[static_cast<std::size_t>(i)] - '0' : 0);
  }
  return atto;
}

// A decimal number [+-]digits[.digits][(e|E)[+-]digits] in units of 10^unit_exponent s.
bool parse_decimal(std::string_view cell, int unit_exponent, TimeStamp& stamp, std::string* problem) {
  auto fail = [&](const std::string& what) {
    if (problem != nullptr) *problem = what;
    return false;
  };
  std::size_t at = 0;
  bool negative = false;
  if (at < cell.size() && (cell[at] == '+' || cell[at] == '-')) negative = cell[at++] == '-';
  std::string digits;
  long integer_digits = 0;
  bool point = false;
  for (; at < cell.size(); ++at) {
    const char c = cell[at];
    if (is_digit(c)) {
      digits += c;
      if (!point) ++integer_digits;
    } else if (c == '.' && !point) {
      point = true;
    } else {
      break;
    }
  }
  if (digits.empty()) return fail(cell.empty() ? "empty cell, expected a number" : fmt::format("'{}' is not a number", excerpt(cell)));
  long exponent = 0;
  if (at < cell.size() && (cell[at] == 'e' || cell[at] == 'E')) {
    ++at;
    const char* begin = cell.data() + at;
    if (at < cell.size() && cell[at] == '+') ++begin;
    const auto result = std::from_chars(begin, cell.data() + cell.size(), exponent);
    if (result.ec == std::errc::result_out_of_range) return fail(fmt::format("'{}' is out of the range of a time", excerpt(cell)));
    if (result.ec != std::errc{}) return fail(fmt::format("'{}' is not a number", excerpt(cell)));
    at = static_cast<std::size_t>(result.ptr - cell.data());
  }
  if (at != cell.size()) return fail(fmt::format("'{}' is not a number", excerpt(cell)));
  // An exponent beyond any number of digits a line can hold: too large a time, or one below
  // an attosecond (0). Settled here, before the sum below that it would overflow.
  constexpr long kMaxExponent = 1'000'000'000;
  if (exponent > kMaxExponent) return fail(fmt::format("'{}' is out of the range of a time", excerpt(cell)));
  if (exponent < -kMaxExponent) {
    stamp = TimeStamp{};
    return true;
  }

  // The digits with the decimal point `position` digits from their start, in seconds.
  const auto first = std::min(digits.find_first_not_of('0'), digits.size());
  const std::string_view significant = std::string_view(digits).substr(first);
  stamp = TimeStamp{};
  if (significant.empty()) return true;
  const long position = integer_digits - static_cast<long>(first) + exponent + unit_exponent;
  if (position > kMaxIntegerDigits) {
    return fail(fmt::format("'{}' is out of the range of a time (10^{} s or more)", excerpt(cell), kMaxIntegerDigits));
  }
  if (position < -kAttoDigits) return true;  // below an attosecond: 0, without a string of zeros as long
  const auto length = static_cast<long>(significant.size());
  for (long i = 0; i < position; ++i) stamp.seconds = stamp.seconds * 10 + (i < length ? significant[static_cast<std::size_t>(i)] - '0' : 0);
  std::string fraction(static_cast<std::size_t>(std::max(0L, -position)), '0');
  if (position < length) fraction += significant.substr(static_cast<std::size_t>(std::max(0L, position)));
  stamp.attoseconds = attoseconds_of(fraction);
  if (negative) negate(stamp);
  return true;
}

bool leap_year(std::int64_t year) { return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0; }

unsigned days_in_month(std::int64_t year, unsigned month) {
  constexpr unsigned kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month == 2 && leap_year(year) ? 29 : kDays[month - 1];
}

// YYYY-MM-DD(T| )hh:mm:ss[(.|,)fraction][Z|(+|-)hh[:mm]|(+|-)hhmm], read left to right;
// the first thing out of place is named with its character position.
class IsoReader {
 public:
  explicit IsoReader(std::string_view cell) : cell_(cell) {}

  bool read(TimeStamp& stamp, std::string* problem) {
    int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
    if (!number(4, year, "a four-digit year") || !literal("-", "'-' after the year") ||
        !number(2, month, "a two-digit month", 1, 12) || !literal("-", "'-' after the month") ||
        !number(2, day, "a two-digit day", 1, 31)) {
      return report(problem);
    }
    if (static_cast<unsigned>(day) > days_in_month(year, static_cast<unsigned>(month))) {
      at_ -= 2;
      expected_ = fmt::format("a day of {:04}-{:02} (01-{:02})", year, month, days_in_month(year, static_cast<unsigned>(month)));
      return report(problem);
    }
    if (!literal("Tt ", "'T' or a space between date and time") || !number(2, hour, "two-digit hours (00-23)", 0, 23) ||
        !literal(":", "':' after the hours") || !number(2, minute, "two-digit minutes (00-59)", 0, 59) ||
        !literal(":", "':' after the minutes") || !number(2, second, "two-digit seconds (00-59)", 0, 59)) {
      return report(problem);
    }
    std::int64_t atto = 0;
    if (at_ < cell_.size() && (cell_[at_] == '.' || cell_[at_] == ',')) {
      const std::size_t start = ++at_;
      while (at_ < cell_.size() && is_digit(cell_[at_])) ++at_;
      if (at_ == start) {
        expected_ = "digits of a fraction of a second";
        return report(problem);
      }
      atto = attoseconds_of(cell_.substr(start, at_ - start));
    }
    int offset_seconds = 0;
    if (at_ < cell_.size() && (cell_[at_] == 'Z' || cell_[at_] == 'z')) {
      ++at_;
    } else if (at_ < cell_.size() && (cell_[at_] == '+' || cell_[at_] == '-')) {
      const int sign = cell_[at_++] == '-' ? -1 : 1;
      int offset_hours = 0, offset_minutes = 0;
      if (!number(2, offset_hours, "two-digit hours of the UTC offset (00-23)", 0, 23)) return report(problem);
      if (at_ < cell_.size()) {
        if (cell_[at_] == ':') ++at_;
        if (!number(2, offset_minutes, "two-digit minutes of the UTC offset (00-59)", 0, 59)) return report(problem);
      }
      offset_seconds = sign * (offset_hours * 3600 + offset_minutes * 60);
    } else if (at_ < cell_.size()) {
      expected_ = "a fraction, 'Z' or a UTC offset (+hh:mm) after the seconds";
      return report(problem);
    }  // no zone: the logger's local clock, read as UTC (differences exact but across a DST change)
    if (at_ != cell_.size()) {
      expected_ = "the end of the time stamp";
      return report(problem);
    }
    stamp = TimeStamp{};
    stamp.seconds = days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day)) * 86400 +
                    hour * 3600 + minute * 60 + second - offset_seconds;
    stamp.attoseconds = atto;
    stamp.iso = true;
    return true;
  }

 private:
  bool number(int width, int& value, const char* what, int low = 0, int high = 9999) {
    value = 0;
    for (int i = 0; i < width; ++i) {
      if (at_ + static_cast<std::size_t>(i) >= cell_.size() || !is_digit(cell_[at_ + static_cast<std::size_t>(i)])) {
        expected_ = what;
        return false;
      }
      value = value * 10 + (cell_[at_ + static_cast<std::size_t>(i)] - '0');
    }
    if (value < low || value > high) {
      expected_ = what;
      return false;
    }
    at_ += static_cast<std::size_t>(width);
    return true;
  }

  bool literal(std::string_view allowed, const char* what) {
    if (at_ < cell_.size() && allowed.find(cell_[at_]) != std::string_view::npos) {
      ++at_;
      return true;
    }
    expected_ = what;
    return false;
  }

  bool report(std::string* problem) const {
    if (problem != nullptr) {
      *problem = fmt::format("'{}' is not an ISO 8601 time stamp: expected {} at character {}", excerpt(cell_), expected_, at_ + 1);
    }
    return false;
  }

  std::string_view cell_;
  std::size_t at_ = 0;
  std::string expected_;
};

}  // namespace

TimeUnit parse_time_unit(std::string_view name) {
  if (name == "s") return TimeUnit::s;
  if (name == "ms") return TimeUnit::ms;
  if (name == "us") return TimeUnit::us;
  if (name == "ns") return TimeUnit::ns;
  throw UsageError(fmt::format("unknown time unit '{}' (expected s, ms, us or ns)", name));
}

std::string_view to_string(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::s: return "s";
    case TimeUnit::ms: return "ms";
    case TimeUnit::us: return "us";
    case TimeUnit::ns: return "ns";
  }
  return "s";
}

int decimal_exponent(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::s: return 0;
    case TimeUnit::ms: return -3;
    case TimeUnit::us: return -6;
    case TimeUnit::ns: return -9;
  }
  return 0;
}

double TimeStamp::seconds_since(const TimeStamp& origin) const {
  const std::int64_t whole = seconds - origin.seconds;
  const std::int64_t atto = attoseconds - origin.attoseconds;  // |atto| < 10^18
  // 10^18 is a double exactly: the fraction of a stamp in ns, µs or ms divides with one rounding.
  return static_cast<double>(whole) + static_cast<double>(atto) / 1e18;
}

double TimeStamp::approximate_seconds() const { return seconds_since(TimeStamp{}); }

bool looks_like_iso_8601(std::string_view cell) {
  return cell.size() > 4 && std::all_of(cell.begin(), cell.begin() + 4, is_digit) && cell[4] == '-';
}

bool parse_time_stamp(std::string_view cell, TimeUnit unit, TimeStamp& stamp, std::string* problem) {
  if (looks_like_iso_8601(cell)) return IsoReader(cell).read(stamp, problem);
  return parse_decimal(cell, decimal_exponent(unit), stamp, problem);
}

std::int64_t days_from_civil(std::int64_t year, unsigned month, unsigned day) {
  year -= month <= 2 ? 1 : 0;
  const std::int64_t era = (year >= 0 ? year : year - 399) / 400;
  const auto year_of_era = static_cast<unsigned>(year - era * 400);                    // [0, 399]
  const unsigned day_of_year = (153 * (month > 2 ? month - 3 : month + 9) + 2) / 5 + day - 1;  // [0, 365]
  const unsigned day_of_era = year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_year;
  return era * 146097 + static_cast<std::int64_t>(day_of_era) - 719468;
}

}  // namespace thermodrift
