#include "thermodrift/sim/chamber_profile.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::sim {
namespace {

TEST(ChamberProfile, DefaultCycleIsSoakRampSoakRampSoakRamp) {
  const ChamberProfile profile{SimulatorOptions{}};
  // Per cycle: 60 min at 20 °C, 40 min up to 60, 60 min soak, 100 min down to -40,
  // 60 min soak, 60 min back to 20: 380 min.
  ASSERT_EQ(profile.segments().size(), 12u);
  EXPECT_DOUBLE_EQ(profile.duration_s(), 2 * 380 * 60.0);
  ASSERT_EQ(profile.cycle_starts_s().size(), 2u);
  EXPECT_DOUBLE_EQ(profile.cycle_starts_s()[0], 0.0);
  EXPECT_DOUBLE_EQ(profile.cycle_starts_s()[1], 380 * 60.0);
  const std::vector<double> expected_end_c = {20, 60, 60, -40, -40, 20};
  const std::vector<double> expected_minutes = {60, 40, 60, 100, 60, 60};
  for (std::size_t i = 0; i < 6; ++i) {
    const auto& segment = profile.segments()[i];
    EXPECT_DOUBLE_EQ(segment.end_c, expected_end_c[i]) << "segment " << i;
    EXPECT_DOUBLE_EQ(segment.end_s - segment.start_s, expected_minutes[i] * 60.0) << "segment " << i;
  }
}

TEST(ChamberProfile, InterpolatesAndClamps) {
  const ChamberProfile profile{SimulatorOptions{}};
  EXPECT_DOUBLE_EQ(profile.temperature_c(-5.0), 20.0);
  EXPECT_DOUBLE_EQ(profile.temperature_c(3600.0 + 600.0), 30.0);  // 10 min into the 1 °C/min ramp
  EXPECT_DOUBLE_EQ(profile.temperature_c(1e9), 20.0);
}

TEST(ChamberProfile, CanCoolFirst) {
  SimulatorOptions options;
  options.heat_first = false;
  const ChamberProfile profile(options);
  EXPECT_DOUBLE_EQ(profile.segments()[1].end_c, -40.0);
  EXPECT_DOUBLE_EQ(profile.segments()[3].end_c, 60.0);
}

TEST(ChamberRunProfile, HitsBothExtremesAndRampsAtOneDegreePerMinute) {
  const ChamberRun run = simulate(SimulatorOptions{});
  const std::vector<double>& chamber = run.column("temp_chamber");
  EXPECT_DOUBLE_EQ(*std::max_element(chamber.begin(), chamber.end()), 60.0);
  EXPECT_DOUBLE_EQ(*std::min_element(chamber.begin(), chamber.end()), -40.0);
  std::size_t ramp_samples = 0;
  std::size_t soak_samples = 0;
  for (std::size_t k = 1; k < chamber.size(); ++k) {
    const double rate_c_per_min = (chamber[k] - chamber[k - 1]) * 60.0;  // 1 Hz
    if (std::abs(rate_c_per_min) < 1e-9) {
      ++soak_samples;
    } else {
      ++ramp_samples;
      EXPECT_NEAR(std::abs(rate_c_per_min), 1.0, 1e-9) << "at row " << k;
    }
  }
  // 200 min of ramps and 180 min of soaks per cycle; the rows stop one step before the
  // end of the final ramp.
  EXPECT_EQ(ramp_samples, 2u * 200 * 60 - 1);
  EXPECT_EQ(soak_samples, 2u * 180 * 60);
}

TEST(ChamberRunProfile, CycleCountAndDurationFollowTheOptions) {
  const ChamberRun two = simulate(SimulatorOptions{});
  EXPECT_EQ(two.rows(), 45600u);  // two 380-min cycles at 1 Hz
  EXPECT_EQ(two.cycle_boundaries(), (std::vector<double>{0.0, 22800.0}));
  EXPECT_EQ(two.cycle_start_rows(), (std::vector<std::size_t>{0, 22800}));
  EXPECT_DOUBLE_EQ(two.column("time_s").back(), 45599.0);

  SimulatorOptions options;
  options.cycles = 3;
  options.rate_hz = 2.0;
  const ChamberRun three = simulate(options);
  EXPECT_EQ(three.rows(), 3u * 22800 * 2);
  EXPECT_EQ(three.cycle_start_rows(), (std::vector<std::size_t>{0, 45600, 91200}));
  EXPECT_DOUBLE_EQ(three.column("time_s")[1], 0.5);
}

}  // namespace
}  // namespace thermodrift::sim
