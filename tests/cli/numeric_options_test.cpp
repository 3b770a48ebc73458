// Numeric options refuse NaN, infinities and trailing junk with one line saying what is
// expected and exit status 2 (CLI11's own checks let NaN through: `--rate nan` was taken
// as "not given", and printed DBL_MAX in 309 digits for an out-of-range value).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(NumericOptions, NanInfinityAndJunkAreUsageErrors) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  const std::string fit = "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json ";
  for (const std::string option : {"--rate nan", "--rate inf", "--rate 1x", "--smooth nan", "--smooth -inf",
                                   "--rate-span nan", "--C nan", "--sigma inf", "--epsilon nan", "--evaluations 0"}) {
    SCOPED_TRACE(option);
    const auto result = run_thermodrift(dir, fit + option);
    EXPECT_EQ(result.status, 2);
    const std::string flag = option.substr(0, option.find(' '));
    EXPECT_NE(result.err.find(flag + ": expected a finite number"), std::string::npos) << result.err;
    EXPECT_LT(result.err.size(), 200u) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
  }
  ASSERT_EQ(run_thermodrift(dir, fit).status, 0);
  const auto settle = run_thermodrift(dir, "evaluate --model m.json --data log.csv --settle nan");
  EXPECT_EQ(settle.status, 2);
  EXPECT_NE(settle.err.find("--settle: expected a finite number of 0 or more, not 'nan'"), std::string::npos)
      << settle.err;
}

}  // namespace
}  // namespace thermodrift::testing
