// Burst logs: each burst of fast samples becomes its mean; ordinary logs, with or without
// dropouts, are left as they are.
#include <gtest/gtest.h>

#include <cmath>

#include "../../support/chamber_logs.hpp"
#include "thermodrift/io/bursts.hpp"

namespace thermodrift {
namespace {

// `bursts` bursts of `per_burst` samples `step` s apart, one every `period` s; gyro = time,
// temperature = 2·time, so each burst's means are known in closed form.
ChamberLog burst_log(int bursts, int per_burst, double step, double period) {
  std::vector<double> time, gyro, temperature;
  for (int b = 0; b < bursts; ++b) {
    for (int k = 0; k < per_burst; ++k) {
      const double t = b * period + k * step;
      time.push_back(t);
      gyro.push_back(t);
      temperature.push_back(2 * t);
    }
  }
  return testing::one_axis_log(time, gyro, temperature, "bursts.csv");
}

TEST(Bursts, FiveSecondsAtFiftyHertzEveryFiveMinutes) {
  const ChamberLog log = burst_log(12, 250, 0.02, 300);
  const auto bursts = find_bursts(log, 200);
  ASSERT_TRUE(bursts);
  EXPECT_EQ(bursts->bursts, 12u);
  EXPECT_EQ(bursts->rows, 3000u);
  EXPECT_EQ(bursts->median_samples, 250);
  EXPECT_NEAR(bursts->median_duration_s, 4.98, 1e-9);
  EXPECT_NEAR(bursts->period_s, 300, 1e-9);
  EXPECT_NEAR(bursts->gap_seconds(), 750, 1e-9);
  EXPECT_EQ(bursts->describe(), "12 bursts of 250 samples (4.98 s) every 300 s");

  const ChamberLog means = collapse_bursts(log, *bursts);
  ASSERT_EQ(means.rows(), 12u);
  ASSERT_TRUE(means.bursts);
  for (std::size_t b = 0; b < means.rows(); ++b) {
    const double centre = static_cast<double>(b) * 300 + 249 * 0.02 / 2;  // mean time of the burst
    EXPECT_NEAR(means.time[b], centre, 1e-9);
    EXPECT_NEAR(means.gyro[0][b], centre, 1e-9);
    EXPECT_NEAR(means.temperature[0][b], 2 * centre, 1e-9);
    EXPECT_EQ(means.line[b], 2 + 250 * b);  // the line of the burst's first row
  }
  EXPECT_FALSE(find_bursts(means, 200)) << "collapsed twice";
}

// binned: the rows of each bin of `seconds` (from the first row's time) become their mean;
// a gap leaves no row, so the step across it stays a gap. Times are binary fractions, so
// every row falls in its bin exactly.
TEST(Bursts, BinnedAveragesEachBinAndKeepsGaps) {
  ChamberLog log = burst_log(1, 800, 0.125, 0);  // 100 s at 8 Hz: t = 0, 0.125, ..., 99.875
  for (std::size_t i = 480; i < log.rows(); ++i) log.time[i] += 50.0625;  // a 50 s dropout after t = 59.875
  const ChamberLog bins = binned(log, 1.0);
  ASSERT_EQ(bins.rows(), 100u);
  EXPECT_FALSE(bins.bursts);
  for (std::size_t b = 0; b < bins.rows(); ++b) {
    const double gyro = static_cast<double>(b) + 0.4375;  // the mean of b, b + 0.125, ..., b + 0.875
    const double shift = b < 60 ? 0 : 50.0625;
    EXPECT_NEAR(bins.time[b], gyro + shift, 1e-9) << b;
    EXPECT_NEAR(bins.gyro[0][b], gyro, 1e-9) << b;
    EXPECT_NEAR(bins.temperature[0][b], 2 * gyro, 1e-9) << b;
    EXPECT_EQ(bins.line[b], 2 + 8 * b);
  }
  EXPECT_NEAR(bins.time[60] - bins.time[59], 51.0625, 1e-9);
  // Bins narrower than the steps between rows change nothing.
  EXPECT_EQ(binned(log, 0.0625).rows(), log.rows());
}

TEST(Bursts, OrdinaryLogsAreLeftAsTheyAre) {
  // A 1 Hz log with two 30 s dropouts: its stretches are hours long, each warms up by itself.
  ChamberLog dropouts = burst_log(1, 20000, 1, 0);
  for (std::size_t i = 7000; i < dropouts.rows(); ++i) dropouts.time[i] += 30;
  for (std::size_t i = 14000; i < dropouts.rows(); ++i) dropouts.time[i] += 30;
  EXPECT_FALSE(find_bursts(dropouts, 200));
  // Ten-minute bursts are longer than the warm-up: ordinary segments.
  EXPECT_FALSE(find_bursts(burst_log(6, 600, 1, 3600), 200));
  // Two bursts are too few to tell a burst log from a log with one gap.
  EXPECT_FALSE(find_bursts(burst_log(2, 250, 0.02, 300), 200));
  // Bursts with shorter gaps than the bursts: a log with dropouts, not bursts.
  EXPECT_FALSE(find_bursts(burst_log(10, 100, 1, 150), 200));
  const ChamberLog kept = collapse_if_bursts(dropouts, 200);
  EXPECT_EQ(kept.rows(), dropouts.rows());
  EXPECT_FALSE(kept.bursts);
}

}  // namespace
}  // namespace thermodrift
