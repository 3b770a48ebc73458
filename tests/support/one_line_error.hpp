// The error contract of a failed command (docs/cli.md): stderr is exactly one line,
// starting "thermodrift: ".
#pragma once

#include <gtest/gtest.h>

#include <algorithm>

#include "temp_dir.hpp"

namespace thermodrift::testing {

inline void expect_one_line(const CommandResult& result) {
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_TRUE(result.err.starts_with("thermodrift: ")) << result.err;
  EXPECT_TRUE(result.err.ends_with("\n")) << result.err;
}

}  // namespace thermodrift::testing
