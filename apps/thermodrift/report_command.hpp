// Shared by report and demo: progress lines and the two tables on the terminal.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <string>

namespace thermodrift::cli {

// "PREFIX [  12.3 s] LINE" on stderr, time counted from `start`.
std::function<void(const std::string&)> progress_printer(const std::string& prefix,
                                                         std::chrono::steady_clock::time_point start);

// The in-sample and held-out tables of a report's summary, on stdout.
void print_report_tables(const nlohmann::json& summary);

}  // namespace thermodrift::cli
