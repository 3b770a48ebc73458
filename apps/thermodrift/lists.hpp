// Comma-separated list options (--gyro, --temp, --features; --temp-scale, --temp-offset,
// --gyro-scale). CLI11's delimiter drops empty items: `--features ,` became no value at
// all, reported as "--out is required", `--gyro a,,b` quietly two axes, and
// `--temp-scale 1,,2` two scales for three columns. The text is split here instead, and an
// empty item refused.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace thermodrift::cli {

namespace detail {
// Each occurrence "a,b,c" (or values after one flag) as its items; `expected` names them.
inline std::vector<std::string> list_items(const std::string& name, const std::vector<std::string>& texts,
                                           const std::string& expected) {
  std::vector<std::string> items;
  for (const auto& text : texts) {
    for (std::size_t start = 0;;) {
      const auto cut = text.find(',', start);
      std::string item = text.substr(start, cut == std::string::npos ? std::string::npos : cut - start);
      if (item.empty()) throw CLI::ValidationError(name, "expected " + expected + " separated by single commas, not '" + text + "'");
      items.push_back(std::move(item));
      if (cut == std::string::npos) break;
      start = cut + 1;
    }
  }
  return items;
}
}  // namespace detail

// Declares `name` as a list of names: its items go to `into`, which keeps its default when
// the option is not given.
inline CLI::Option* add_list_option(CLI::App& app, const std::string& name, std::vector<std::string>& into,
                                    const std::string& help) {
  return app.add_option_function<std::vector<std::string>>(
      name, [&into, name](const std::vector<std::string>& texts) { into = detail::list_items(name, texts, "names"); },
      help);
}

// Declares `name` as a list of finite numbers.
inline CLI::Option* add_number_list_option(CLI::App& app, const std::string& name, std::vector<double>& into,
                                           const std::string& help) {
  return app
      .add_option_function<std::vector<std::string>>(
          name,
          [&into, name](const std::vector<std::string>& texts) {
            into.clear();
            for (const auto& item : detail::list_items(name, texts, "numbers")) {
              double value = 0;
              std::size_t used = 0;
              try {
                value = std::stod(item, &used);
              } catch (const std::exception&) {
                used = 0;
              }
              if (used != item.size() || !std::isfinite(value)) {
                throw CLI::ValidationError(name, "expected a finite number, not '" + item + "'");
              }
              into.push_back(value);
            }
          },
          help)
      ->type_name("FLOAT");
}

}  // namespace thermodrift::cli
