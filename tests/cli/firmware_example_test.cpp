// examples/firmware_loop.c, built and run as examples/README.md says: it compiles against
// an exported header with the strictest C99 flags and prints what its comment narrates.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

std::string without_trailing_spaces(std::string line) {
  line.erase(line.find_last_not_of(' ') + 1);
  return line;
}

// The lines the example's comment shows as its output (" *   t=..." and " *   dropped...").
std::vector<std::string> narrated_output(const std::string& source) {
  std::vector<std::string> lines;
  for (const auto& line : split_lines(source)) {
    if (line.rfind(" *   t=", 0) == 0 || line.rfind(" *   dropped", 0) == 0) lines.push_back(line.substr(5));
  }
  return lines;
}

TEST(FirmwareExample, BuildsAgainstAnExportedHeaderAndPrintsWhatItsCommentSays) {
  const std::string example = std::string(THERMODRIFT_SOURCE_DIR) + "/examples/firmware_loop.c";
  const std::vector<std::string> expected = narrated_output(read_file(example));
  ASSERT_GE(expected.size(), 5u);
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --out chamber.csv --cycles 1").status, 0);
  ASSERT_EQ(run_thermodrift(dir, "fit --data chamber.csv --gyro gyro_x,gyro_y,gyro_z --temp temp_x,temp_y,temp_z "
                                 "--model linear --out model.json")
                .status,
            0);
  ASSERT_EQ(run_thermodrift(dir, "export --model model.json --out thermodrift_model.h --max-rate 1").status, 0);
  const auto built =
      run_in(dir, "gcc -std=c99 -Wall -Wextra -Werror -pedantic -O2 -I. '" + example + "' -o firmware_loop -lm");
  ASSERT_EQ(built.status, 0) << built.err;
  const auto ran = run_in(dir, "./firmware_loop");
  ASSERT_EQ(ran.status, 0) << ran.err;
  std::vector<std::string> printed;
  for (const auto& line : split_lines(ran.out)) printed.push_back(without_trailing_spaces(line));
  EXPECT_EQ(printed, expected) << ran.out;
}

}  // namespace
}  // namespace thermodrift::testing
