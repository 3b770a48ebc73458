// docs/cli.md shows every command's options as the built tool's --help prints them, so the
// reference cannot drift from the tool (scripts/cli-reference regenerates it).
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(CliReference, DocsShowEveryCommandsHelpAsTheToolPrintsIt) {
  const std::string reference = read_file(std::string(THERMODRIFT_SOURCE_DIR) + "/docs/cli.md");
  ASSERT_FALSE(reference.empty());
  TempDir dir;
  for (const std::string command : {"", "simulate", "fit", "evaluate", "compensate", "compress", "export", "report", "demo"}) {
    SCOPED_TRACE(command);
    const auto help = run_thermodrift(dir, command + " --help");
    ASSERT_EQ(help.status, 0) << help.err;
    // The usage line names the binary as it was called; the reference names it as users do.
    const std::string as_documented =
        std::regex_replace(help.out, std::regex("Usage: [^ ]*thermodrift"), "Usage: thermodrift");
    const std::string heading = "### `thermodrift" + (command.empty() ? "" : " " + command) + "`\n\n```\n";
    EXPECT_NE(reference.find(heading + as_documented + "```\n"), std::string::npos)
        << "docs/cli.md differs from `thermodrift " << command
        << " --help`: run scripts/cli-reference after building";
  }
}

}  // namespace
}  // namespace thermodrift::testing
