#include "commands.hpp"

namespace thermodrift::cli {

std::vector<Command> register_commands(CLI::App& app) {
  std::vector<Command> commands;
  for (auto add : {add_simulate, add_fit, add_evaluate, add_compensate, add_report, add_demo, add_export, add_compress}) {
    commands.push_back(add(app));
  }
  return commands;
}

int run_selected(const std::vector<Command>& commands) {
  for (const auto& command : commands) {
    if (command.app->parsed()) return command.run();
  }
  return 2;
}

}  // namespace thermodrift::cli
