// The subcommands of the thermodrift tool. Each `add_*` declares its options on a new
// CLI11 subcommand and returns the action to run once parsing succeeded.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace thermodrift::cli {

using Action = std::function<int()>;

struct Command {
  CLI::App* app = nullptr;
  Action run;
};

Command add_simulate(CLI::App& parent);
Command add_fit(CLI::App& parent);
Command add_evaluate(CLI::App& parent);
Command add_compensate(CLI::App& parent);
Command add_demo(CLI::App& parent);
Command add_report(CLI::App& parent);
Command add_export(CLI::App& parent);
Command add_compress(CLI::App& parent);

std::vector<Command> register_commands(CLI::App& app);
int run_selected(const std::vector<Command>& commands);

}  // namespace thermodrift::cli
