// Checks of numeric options. CLI11's PositiveNumber lets NaN through (NaN <= 0 is false),
// so `--rate nan` was taken as "not given", and its range message printed DBL_MAX in 309
// digits; these say what is expected in one line and refuse NaN and infinities.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
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
// The SVR's C and γ: above 0 and within the ±1e12 every number of a model file stays
// within (a larger one is refused at load: it is a failed fit or an edited file).
inline const CLI::Validator kModelScale = detail::finite_at_least(0, true, "a finite number above 0 and at most 1e12", 1e12);
// σ: γ = 1/(2σ²) at most 1e12.
inline const CLI::Validator kKernelWidth = detail::finite_at_least(1e-6, false, "a finite number of at least 1e-6", HUGE_VAL, "POSITIVE");
// A finite number >= 0 (smoothing, settling, ε).
inline const CLI::Validator kNonNegative = detail::finite_at_least(0, false, "a finite number of 0 or more");

}  // namespace thermodrift::cli
