// Checks of numeric options. CLI11's PositiveNumber lets NaN through (NaN <= 0 is false),
// so `--rate nan` was taken as "not given", and its range message printed DBL_MAX in 309
// digits; these say what is expected in one line and refuse NaN and infinities.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace thermodrift::cli {

namespace detail {
inline CLI::Validator finite_at_least(double low, bool strict, const std::string& expected,
                                      double high = HUGE_VAL, const char* name = nullptr) {
  return CLI::Validator(
      [low, strict, expected, high](std::string& text) -> std::string {
        double value = 0;
        std::size_t used = 0;
        try {
          value = std::stod(text, &used);
        } catch (const std::exception&) {
          return "expected " + expected + ", not '" + text + "'";
        }
        if (used != text.size() || !std::isfinite(value) || (strict ? !(value > low) : !(value >= low)) ||
            value > high) {
          return "expected " + expected + ", not '" + text + "'";
        }
        return {};
      },
      name != nullptr ? name : strict ? "POSITIVE" : "NON-NEGATIVE");
}
}  // namespace detail

// A finite number > 0 (rates, spans, C, σ, counts).
inline const CLI::Validator kPositive = detail::finite_at_least(0, true, "a finite number above 0");
// A log's sampling rate (Hz): a row's time is its number over it, so a subnormal rate made
// every time infinite. The floor is a model file's (rate_hz at least 1e-12 Hz).
inline const CLI::Validator kSampleRate =
    detail::finite_at_least(1e-12, false, "a finite number of hertz of at least 1e-12", HUGE_VAL, "POSITIVE");
// The SVR's C and γ: above 0 and within the ±1e12 every number of a model file stays
// within (a larger one is refused at load: it is a failed fit or an edited file).
inline const CLI::Validator kModelScale = detail::finite_at_least(0, true, "a finite number above 0 and at most 1e12", 1e12);
// σ: γ = 1/(2σ²) at most 1e12.
inline const CLI::Validator kKernelWidth = detail::finite_at_least(1e-6, false, "a finite number of at least 1e-6", HUGE_VAL, "POSITIVE");
// A chamber temperature (°C) within the physical range a log may hold (io/chamber_log.hpp).
inline const CLI::Validator kCelsius =
    detail::finite_at_least(-273.15, false, "a temperature from -273.15 to 1000 °C", 1000, "CELSIUS");
// A finite number >= 0 (smoothing, settling, ε).
inline const CLI::Validator kNonNegative = detail::finite_at_least(0, false, "a finite number of 0 or more");

// A whole number in [low, high], in decimal digits only. CLI11 took `--seed -1` and
// `--seed 18446744073709551616` as some other seed without a word, and answered
// `--decimate 1e9` with "Could not convert".
// (Unnamed: the help shows the option's type, the message the range.)
inline CLI::Validator whole_number(std::uint64_t low, std::uint64_t high) {
  const std::string expected = "a whole number from " + std::to_string(low) + " to " + std::to_string(high);
  return CLI::Validator(
      [low, high, expected](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, value);
        if (text.empty() || stop != end || error != std::errc{} || value < low || value > high) {
          return "expected " + expected + ", not '" + text + "'";
        }
        return {};
      },
      "");
}

// Seeds: any 64-bit unsigned number.
inline const CLI::Validator kSeed = whole_number(0, std::numeric_limits<std::uint64_t>::max());
// Worker threads, and tuning budgets: what a navigation lab's machine could use.
inline const CLI::Validator kThreads = whole_number(1, 1024);
inline const CLI::Validator kEvaluations = whole_number(1, 1000000);

}  // namespace thermodrift::cli
