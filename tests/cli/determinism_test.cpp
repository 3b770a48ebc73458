// The same inputs and seed give byte-identical model files, run after run and with 1 or
// 2 threads: tuning evaluates in parallel, but its result may not depend on scheduling.
#include <gtest/gtest.h>

#include <string>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

TEST(Determinism, TunedSvrModelFileIsByteIdenticalWhateverTheThreadCount) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.25 --seed 7 --out log.csv").status, 0);
  const std::string fit =
      "fit --data log.csv --gyro gyro_x,gyro_y --temp temp_x,temp_y --model svr --tune afsa "
      "--evaluations 9 ";
  for (const char* name : {"one.json", "two.json", "again.json"}) {
    const std::string threads = std::string(name) == "two.json" ? "2" : "1";
    const auto result = run_thermodrift(dir, fit + "--seed 3 --threads " + threads + " --out " + name);
    ASSERT_EQ(result.status, 0) << result.err;
  }
  const std::string one = read_file(dir.file("one.json"));
  ASSERT_NE(one.find("\"tuning\""), std::string::npos);  // it really was tuned
  EXPECT_EQ(one, read_file(dir.file("two.json")));
  EXPECT_EQ(one, read_file(dir.file("again.json")));

  // A different seed is a different search: the check above can fail.
  ASSERT_EQ(run_thermodrift(dir, fit + "--threads 2 --seed 4 --out other.json").status, 0);
  EXPECT_NE(one, read_file(dir.file("other.json")));
}

// The feature search runs the axes in parallel with --threads > 1: the same terms and
// coefficients as one axis after another.
TEST(Determinism, FeatureSearchGivesTheSameModelWhateverTheThreadCount) {
  TempDir dir;
  ASSERT_EQ(run_thermodrift(dir, "simulate --cycles 1 --rate 0.25 --seed 7 --out log.csv").status, 0);
  const std::string fit =
      "fit --data log.csv --gyro gyro_x,gyro_y,gyro_z --temp temp_x,temp_y,temp_z --model linear --features auto ";
  for (const char* threads : {"1", "3"}) {
    const auto result = run_thermodrift(dir, fit + "--threads " + threads + " --out t" + threads + ".json");
    ASSERT_EQ(result.status, 0) << result.err;
  }
  const std::string one = read_file(dir.file("t1.json"));
  ASSERT_NE(one.find("\"feature_selection\""), std::string::npos);  // the terms were searched
  EXPECT_EQ(one, read_file(dir.file("t3.json")));
}

}  // namespace
}  // namespace thermodrift::testing
