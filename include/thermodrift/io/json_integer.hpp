// Integers read from a JSON file. nlohmann's get<int>() on a float such as 1e68 is a
// float-to-int cast out of range (undefined behaviour), so a file's integer fields are
// checked for type and range first.
#pragma once

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <limits>
#include <string_view>
#include <utility>

#include "thermodrift/error.hpp"

namespace thermodrift {

// `value` as a T, or Error("<what> must be an integer from <min> to <max>, not <value>").
template <class T>
T json_integer(const nlohmann::json& value, std::string_view what) {
  if (value.is_number_unsigned()) {
    const auto n = value.get<std::uint64_t>();
    if (std::in_range<T>(n)) return static_cast<T>(n);
  } else if (value.is_number_integer()) {
    const auto n = value.get<std::int64_t>();
    if (std::in_range<T>(n)) return static_cast<T>(n);
  }
  throw Error(fmt::format("{} must be an integer from {} to {}, not {}", what,
                          std::numeric_limits<T>::min(), std::numeric_limits<T>::max(),
                          value.dump()));
}

}  // namespace thermodrift
