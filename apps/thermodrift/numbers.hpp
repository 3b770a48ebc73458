// Checks of numeric options. CLI11's PositiveNumber lets NaN through (NaN <= 0 is false),
// so `--rate nan` was taken as "not given", and its range message printed DBL_MAX in 309
// digits; these say what is expected in one line and refuse NaN and infinities.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace thermodrift::cli {

namespace detail {
inline CLI::Validator finite_at_least(double low, bool strict, const std::string& expected) {
  return CLI::Validator(
      [low, strict, expected](std::string& text) -> std::string {
        double value = 0;
        std::size_t used = 0;
        try {
          value = std::stod(text, &used);
        } catch (const std::exception&) {
          return "expected " + expected + ", not '" + text + "'";
        }
        if (used != text.size() || !std::isfinite(value) || (strict ? !(value > low) : !(value >= low))) {
          return "expected " + expected + ", not '" + text + "'";
        }
        return {};
      },
      strict ? "POSITIVE" : "NON-NEGATIVE");
}
}  // namespace detail

// A finite number > 0 (rates, spans, C, σ, counts).
inline const CLI::Validator kPositive = detail::finite_at_least(0, true, "a finite number above 0");
// A finite number >= 0 (smoothing, settling, ε).
inline const CLI::Validator kNonNegative = detail::finite_at_least(0, false, "a finite number of 0 or more");

}  // namespace thermodrift::cli
