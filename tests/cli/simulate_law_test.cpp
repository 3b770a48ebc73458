// thermodrift simulate --law: a unit of the law family through a drawn programme, written
// with the usual columns; an unknown profile is a usage error of one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "../support/temp_dir.hpp"
#include "thermodrift/sim/chamber_run.hpp"

namespace thermodrift {
namespace {

using testing::CommandResult;
using testing::read_file;
using testing::split_lines;
using testing::TempDir;

using testing::run_thermodrift;

TEST(SimulateLaw, WritesTheChamberRunColumns) {
  TempDir dir;
  const auto result = run_thermodrift(dir, "simulate --law 5 --profile staircase --cycles 1 --out x.csv");
  ASSERT_EQ(result.status, 0) << result.err;
  const auto lines = split_lines(read_file(dir.file("x.csv")));
  ASSERT_GT(lines.size(), 3600u);
  std::string header;
  for (std::string_view name : sim::chamber_run_columns) header += (header.empty() ? "" : ",") + std::string(name);
  EXPECT_EQ(lines.front(), header);
  EXPECT_EQ(std::count(lines.back().begin(), lines.back().end(), ','), 10);
}

TEST(SimulateLaw, DescribePrintsTheDrawnLawOnStderr) {
  TempDir dir;
  const auto result = run_thermodrift(dir, "simulate --law 5 --profile wander --describe --out x.csv");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_TRUE(result.err.starts_with("law 5: range")) << result.err;
  EXPECT_NE(result.err.find("  z: chain"), std::string::npos) << result.err;
}

TEST(SimulateLaw, AnUnknownProfileExitsTwoWithOneLine) {
  TempDir dir;
  const auto result = run_thermodrift(dir, "simulate --law 5 --profile nonsense --out x.csv");
  EXPECT_EQ(result.status, 2);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_TRUE(result.err.starts_with("thermodrift: ")) << result.err;
  EXPECT_NE(result.err.find("nonsense"), std::string::npos) << result.err;
  EXPECT_EQ(dir.entries(), std::vector<std::string>{}) << "no output file on failure";
}

}  // namespace
}  // namespace thermodrift
