// Any argument vector (NUL-separated in the input) through the tool's own CLI11
// parser: it parses or throws a CLI11 parse error; actions are not run.
#include <CLI/CLI.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "commands.hpp"
#include "thermodrift/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> words{"thermodrift"};
  std::string word;
  for (std::size_t i = 0; i < size; ++i) {
    if (data[i] == 0) {
      words.push_back(word);
      word.clear();
    } else {
      word.push_back(static_cast<char>(data[i]));
    }
  }
  if (!word.empty()) words.push_back(word);
  if (words.size() > 40) return 0;
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  CLI::App app{"thermodrift"};
  app.require_subcommand(1);
  const auto commands = thermodrift::cli::register_commands(app);
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::Error&) {
  } catch (const thermodrift::Error&) {
  }
  return 0;
}
