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
  // Built once: building the whole CLI took 3 ms per input under the sanitizers, so 10
  // million inputs were out of reach. CLI11 clears what a parse left (counts, subcommands
  // seen) before the next; the variables options write keep their last values, and only
  // the actions, never run here, read them.
  static CLI::App app{"thermodrift"};
  static const auto commands = [] {
    app.require_subcommand(1);
    return thermodrift::cli::register_commands(app);
  }();
  app.clear();
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::Error&) {
  } catch (const thermodrift::Error&) {
  }
  return 0;
}
