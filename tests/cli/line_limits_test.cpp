// A log line far longer than any log writes (a file without line endings, a binary) is a
// data error at its line, read without holding it whole, and no message echoes a huge cell.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(LineLimits, ALongLineIsADataErrorAndMessagesStayShort) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  auto lines = split_lines(read_file(dir.file("log.csv")));
  std::string text;
  for (std::size_t i = 0; i < lines.size(); ++i) text += (i == 30 ? std::string(3'000'000, '1') : lines[i]) + "\n";
  dir.write("long.csv", text);
  const std::string fit = "fit --gyro gyro_x --temp temp_x --model linear --out m.json --data ";
  const auto result = run_thermodrift(dir, fit + "long.csv");
  EXPECT_EQ(result.status, 3) << result.err.substr(0, 300);
  EXPECT_NE(result.err.find("long.csv:31: line longer than 1048576 bytes"), std::string::npos) << result.err.substr(0, 300);
  EXPECT_LT(result.err.size(), 200u);
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));

  // A 100 kB cell that is not a number (one garbled row: dropped with a warning) is
  // quoted by its first 40 characters.
  text.clear();
  for (std::size_t i = 0; i < lines.size(); ++i) {
    auto cells = cells_of(lines[i]);
    if (i == 30) cells.at(2) = std::string(100'000, 'x');
    text += join_cells(cells) + "\n";
  }
  dir.write("cell.csv", text);
  const auto cell = run_thermodrift(dir, fit + "cell.csv");
  EXPECT_EQ(cell.status, 0) << cell.err.substr(0, 300);
  EXPECT_LT(cell.err.size(), 600u) << cell.err.substr(0, 600);
  EXPECT_NE(cell.err.find("cell.csv:31:3: '" + std::string(40, 'x') + "…' is not a number"), std::string::npos)
      << cell.err.substr(0, 600);
}

}  // namespace
}  // namespace thermodrift::testing
