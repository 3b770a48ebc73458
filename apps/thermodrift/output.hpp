// What fit and evaluate print: one JSON object with --json, else a short table.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace thermodrift::cli {

// `result` holds an "axes" array whose elements carry name, mse_before, mse_after,
// residual_std, residual_peak_to_peak. Prints it as JSON or as a table under `title`.
void print_axes(const nlohmann::json& result, bool as_json, const std::string& title);

}  // namespace thermodrift::cli
