// thermodrift command line: CLI11 subcommands, one file each. This is the only place
// where library exceptions become one line on stderr and an exit status (exit_status.hpp).
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

#include <unistd.h>

#include "commands.hpp"
#include "exit_status.hpp"
#include "interrupt.hpp"
#include "thermodrift/error.hpp"

int main(int argc, char** argv) {
  using thermodrift::cli::ExitStatus;
  CLI::App app{"thermodrift: model and compensate the temperature drift of gyroscopes"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "thermodrift 0.1.0");
  const auto commands = thermodrift::cli::register_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "thermodrift: %s\n", e.what());
    return static_cast<int>(ExitStatus::usage);
  }
  thermodrift::cli::install_interrupt_handler();
  // A reader that goes away (`| head`, a FIFO closed early) must make a write fail with
  // EPIPE, reported as one line and exit 1, not kill the process without a word.
  std::signal(SIGPIPE, SIG_IGN);
  // Into a file or a pipe, what a command prints reaches it at the end, in one flush, so
  // that a failed write is seen with its errno below ("No space left on device"); a write
  // that failed mid-way inside stdio left only its error flag. A terminal stays line-buffered.
  static std::vector<char> stdout_buffer(std::size_t{1} << 20);
  if (::isatty(STDOUT_FILENO) == 0) std::setvbuf(stdout, stdout_buffer.data(), _IOFBF, stdout_buffer.size());
  try {
    const int status = thermodrift::cli::run_selected(commands);
    // What a command printed on stdout (evaluate's table, fit --json, export's summary)
    // must all have reached it: a full disk or a reader gone is exit 1, not 0.
    errno = 0;
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
      std::fprintf(stderr, "thermodrift: cannot write the standard output: %s\n",
                   errno != 0 ? std::strerror(errno) : "a write failed");
      return status != 0 ? status : static_cast<int>(ExitStatus::failure);
    }
    return status;
  } catch (const std::exception& e) {
    // After the first signal every error ends the command as interrupted: a call the
    // signal cut short (EINTR, e.g. opening a FIFO nobody reads) fails with its own error.
    if (dynamic_cast<const thermodrift::Interrupted*>(&e) != nullptr || thermodrift::cli::interrupt_requested()) {
      std::fprintf(stderr, "thermodrift: interrupted (%s); no output written\n", e.what());
      return thermodrift::cli::interrupted_exit_status();
    }
    std::fprintf(stderr, "thermodrift: %s\n", e.what());
    if (dynamic_cast<const thermodrift::UsageError*>(&e) != nullptr) return static_cast<int>(ExitStatus::usage);
    if (dynamic_cast<const thermodrift::DataError*>(&e) != nullptr) return static_cast<int>(ExitStatus::bad_data);
    return static_cast<int>(ExitStatus::failure);
  }
}
