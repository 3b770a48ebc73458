// Comma-separated list options (--gyro, --temp, --features). CLI11's delimiter drops empty
// items: `--features ,` became no value at all, reported as "--out is required", and
// `--gyro a,,b` quietly two axes. The text is split here instead, and an empty item refused.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace thermodrift::cli {

// Declares `name` as a list: each occurrence "a,b,c" (or values after one flag) adds its
// items to `into`, which keeps its default when the option is not given.
inline CLI::Option* add_list_option(CLI::App& app, const std::string& name, std::vector<std::string>& into,
                                    const std::string& help) {
  return app.add_option_function<std::vector<std::string>>(
      name,
      [&into, name](const std::vector<std::string>& texts) {
        into.clear();
        for (const auto& text : texts) {
          for (std::size_t start = 0;;) {
            const auto cut = text.find(',', start);
            const std::string item = text.substr(start, cut == std::string::npos ? std::string::npos : cut - start);
            if (item.empty()) {
              throw CLI::ValidationError(name, "expected names separated by single commas, not '" + text + "'");
            }
            into.push_back(item);
            if (cut == std::string::npos) break;
            start = cut + 1;
          }
        }
      },
      help);
}

}  // namespace thermodrift::cli
