// Options are checked, never silently ignored. Numeric options refuse NaN, infinities and
// trailing junk with one line saying what is expected and exit status 2 (CLI11's own
// checks let NaN through: `--rate nan` was taken as "not given", and an out-of-range value
// printed DBL_MAX in 309 digits).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(OptionChecks, NanInfinityAndJunkAreUsageErrors) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  const std::string fit = "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json ";
  for (const std::string option : {"--rate nan", "--rate inf", "--rate 1x", "--smooth nan", "--smooth -inf",
                                   "--rate-span nan", "--C nan", "--sigma inf", "--epsilon nan"}) {
    SCOPED_TRACE(option);
    const auto result = run_thermodrift(dir, fit + option);
    EXPECT_EQ(result.status, 2);
    const std::string flag = option.substr(0, option.find(' '));
    EXPECT_NE(result.err.find(flag + ": expected a finite number"), std::string::npos) << result.err;
    EXPECT_LT(result.err.size(), 200u) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
  }
  // A rate so small that a row's time (its number over the rate) is infinite.
  const auto tiny_rate = run_thermodrift(dir, "fit --data log.csv --gyro 6 --temp 3 --model linear --out m.json "
                                              "--rate 5e-324");
  EXPECT_EQ(tiny_rate.status, 2);
  EXPECT_NE(tiny_rate.err.find("--rate: expected a finite number of hertz of at least 1e-12, not '5e-324'"),
            std::string::npos)
      << tiny_rate.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
  ASSERT_EQ(run_thermodrift(dir, fit).status, 0);
  const auto settle = run_thermodrift(dir, "evaluate --model m.json --data log.csv --settle nan");
  EXPECT_EQ(settle.status, 2);
  EXPECT_NE(settle.err.find("--settle: expected a finite number of 0 or more, not 'nan'"), std::string::npos)
      << settle.err;
}

// Options that cannot apply are refused, not silently ignored: the SVR's with another
// model, a smoothing window other than the model's when applying it.
TEST(OptionChecks, OptionsThatCannotApplyAreUsageErrors) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  for (const std::string option : {"--C 10", "--sigma 1", "--epsilon 0.1", "--folds 3", "--evaluations 9"}) {
    SCOPED_TRACE(option);
    const auto result = run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --out m.json " + option);
    EXPECT_EQ(result.status, 2);
    EXPECT_NE(result.err.find(option.substr(0, option.find(' ')) + " applies to --model svr, not linear"),
              std::string::npos)
        << result.err;
  }
  // --node-channel chooses where --features auto's thermal node is looked for, --log-start
  // whether it offers the start-of-run terms: nothing else.
  for (const std::string option : {"--node-channel any", "--log-start running"}) {
    for (const std::string features : {"", " --features dT,lag:600", " --features auto --identify greedy"}) {
      SCOPED_TRACE(option + features);
      const auto result = run_thermodrift(dir, "fit --data log.csv --model linear " + option + " --out m.json" + features);
      EXPECT_EQ(result.status, 2);
      EXPECT_NE(result.err.find(option.substr(0, option.find(' ')) +
                                " applies to --features auto with the thermal-node identification"),
                std::string::npos)
          << result.err;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
  ASSERT_EQ(run_thermodrift(dir, "fit --data log.csv --gyro gyro_x --temp temp_x --model linear --smooth 50 --out m.json").status, 0);
  for (const char* command : {"evaluate --model m.json --data log.csv", "compensate --model m.json --data log.csv --out c.csv"}) {
    SCOPED_TRACE(command);
    const auto other = run_thermodrift(dir, std::string(command) + " --smooth 100");
    EXPECT_EQ(other.status, 2);
    EXPECT_NE(other.err.find("the model was fitted with a 50 s window"), std::string::npos) << other.err;
    EXPECT_EQ(run_thermodrift(dir, std::string(command) + " --smooth 50").status, 0);  // the model's: fine
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv.tmp")));
}

// An SVR stopped at its iteration cap is written (it is usable) with a warning; a C beyond
// what a model file may hold is refused before any work.
TEST(OptionChecks, AnUnconvergedSvrIsAWarningAndAnAbsurdCAUsageError) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.2 --out log.csv").status, 0);
  const std::string fit = "fit --data log.csv --gyro gyro_x --temp temp_x --model svr --sigma 1 --out m.json --C ";
  const auto capped = run_thermodrift(dir, fit + "1e12");
  EXPECT_EQ(capped.status, 0) << capped.err;
  EXPECT_NE(capped.err.find("warning: gyro_x: the SVR stopped at its iteration cap"), std::string::npos) << capped.err;
  EXPECT_TRUE(std::filesystem::exists(dir.file("m.json")));
  std::filesystem::remove(dir.file("m.json"));
  const auto absurd = run_thermodrift(dir, fit + "1e300");
  EXPECT_EQ(absurd.status, 2);
  EXPECT_NE(absurd.err.find("--C: expected a finite number above 0 and at most 1e12"), std::string::npos) << absurd.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
}

// One rule for C and σ: tuned together (the paper's AFSA) or both given. An option that
// tuning would override, or that only tuning reads, is refused rather than dropped, as are
// the SVR's kernel options with another model, --identify without --features auto and a
// time column named beside a sampling rate (fit read the column, evaluate the rate).
TEST(OptionChecks, OptionsThatWouldBeDroppedAreUsageErrors) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.1 --out log.csv").status, 0);
  const std::string fit = "fit --data log.csv --gyro gyro_x --temp temp_x --out m.json ";
  for (const auto& [options, expected] : std::vector<std::pair<std::string, std::string>>{
           {"--model linear --kernel nystrom", "--kernel applies to --model svr, not linear"},
           {"--model stepwise --landmarks 100", "--landmarks applies to --model svr, not stepwise"},
           {"--model svr --C 1 --sigma 1 --tune grid", "--C with --tune: tuning chooses C and σ"},
           {"--model svr --gamma 0.5 --tune afsa", "--gamma with --tune"},
           {"--model svr --C 10", "--C alone would be replaced: C and σ are tuned together"},
           {"--model svr --sigma 2", "--sigma alone would be replaced"},
           {"--model svr --C 10 --sigma 1 --evaluations 5", "--evaluations applies when C and σ are tuned"},
           {"--model svr --C 10 --gamma 1 --objective holdout", "--objective applies when C and σ are tuned"},
           {"--model svr --C 10 --sigma 1 --folds 3", "--folds applies when C and σ are tuned"},
           {"--model svr --C 10 --sigma 1 --tune-epsilon", "--tune-epsilon applies when C and σ are tuned"},
           {"--model svr --epsilon 0.3 --tune-epsilon", "--epsilon with --tune-epsilon"},
           {"--model linear --identify greedy", "--identify applies to --features auto"},
           {"--model linear --features auto --keep-kernel", "--keep-kernel applies to --model svr, not linear"},
           {"--model svr --keep-kernel", "--keep-kernel applies to a tuned SVR on --features auto"},
           {"--model svr --C 10 --sigma 1 --features auto --keep-kernel", "--keep-kernel applies to a tuned SVR"},
           {"--model svr --features auto --identify greedy --keep-kernel", "--keep-kernel applies to a tuned SVR"},
           {"--model linear --folds-by runs", "--folds-by applies to the cross-validation of --features auto"},
           {"--model linear --features dT,lag:600 --identify thermal-node", "--identify applies to --features auto"},
           {"--model linear --time time_s --rate 2", "--time and --rate: give one"}}) {
    SCOPED_TRACE(options);
    const auto result = run_thermodrift(dir, fit + options);
    EXPECT_EQ(result.status, 2);
    EXPECT_NE(result.err.find(expected), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.json")));
  }
  for (const char* command : {"report --data log.csv --out r --identify greedy", "demo --out d --identify greedy"}) {
    const auto result = run_thermodrift(dir, command);
    EXPECT_EQ(result.status, 2) << command;
    EXPECT_NE(result.err.find("--identify applies to --features auto"), std::string::npos) << result.err;
  }
  // simulate: the default unit's programme options, or a drawn law's.
  for (const auto& [options, expected] : std::vector<std::pair<std::string, std::string>>{
           {"--profile slow", "--profile applies with --law"},
           {"--describe", "--describe applies with --law"},
           {"--law 3 --ramp 2", "--ramp applies to the default unit, not --law"},
           {"--min-temp nan", "--min-temp: expected a temperature from -273.15 to 1000 °C, not 'nan'"}}) {
    SCOPED_TRACE(options);
    const auto result = run_thermodrift(dir, "simulate --out s.csv " + options);
    EXPECT_EQ(result.status, 2);
    EXPECT_NE(result.err.find(expected), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("s.csv")));
  }
  // What stays: both fixed, tuning with its own options.
  EXPECT_EQ(run_thermodrift(dir, fit + "--model svr --C 10 --sigma 1 --epsilon 0.1").status, 0);
  const auto compress = run_thermodrift(dir, "compress --model m.json --settle 10 --out c.json");
  EXPECT_EQ(compress.status, 2);
  EXPECT_NE(compress.err.find("--settle applies with --data"), std::string::npos) << compress.err;
  EXPECT_EQ(run_thermodrift(dir, fit + "--model svr --tune random --evaluations 4 --folds 3 --tune-epsilon").status, 0);
  ASSERT_EQ(run_thermodrift(dir, fit + "--model linear").status, 0);
  const auto evaluate = run_thermodrift(dir, "evaluate --model m.json --data log.csv --time time_s --rate 2");
  EXPECT_EQ(evaluate.status, 2);
  EXPECT_NE(evaluate.err.find("--time and --rate: give one"), std::string::npos) << evaluate.err;
}

}  // namespace
}  // namespace thermodrift::testing
