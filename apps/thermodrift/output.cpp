#include "output.hpp"

#include <fmt/format.h>

#include <cstdio>

namespace thermodrift::cli {

void print_axes(const nlohmann::json& result, bool as_json, const std::string& title) {
  if (as_json) {
    std::fputs((result.dump(2) + "\n").c_str(), stdout);
    return;
  }
  fmt::print("{}\n", title);
  fmt::print("{:<12} {:>9} {:>14} {:>14} {:>12} {:>12}\n", "axis", "samples", "MSE before", "MSE after",
             "resid std", "resid p-p");
  fmt::print("{:<12} {:>9} {:>14} {:>14} {:>12} {:>12}\n", "", "", "(°/h)²", "(°/h)²", "°/h", "°/h");
  for (const auto& axis : result.at("axes")) {
    fmt::print("{:<12} {:>9} {:>14.6g} {:>14.6g} {:>12.4g} {:>12.4g}\n", axis.at("name").get<std::string>(),
               axis.at("samples").get<std::size_t>(), axis.at("mse_before").get<double>(),
               axis.at("mse_after").get<double>(), axis.at("residual_std").get<double>(),
               axis.at("residual_peak_to_peak").get<double>());
  }
  for (const auto& axis : result.at("axes")) {
    if (!axis.contains("terms")) continue;
    std::string terms;
    for (const auto& term : axis["terms"]) terms += (terms.empty() ? "" : ", ") + term.get<std::string>();
    fmt::print("{} terms: {}\n", axis.at("name").get<std::string>(), terms);
  }
}

}  // namespace thermodrift::cli
