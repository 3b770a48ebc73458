// The noise floor estimated from a log alone (features/noise_floor.hpp) against the
// simulator's true floor, which knows the drift. On the default run at the paper's 100 s
// window the estimate was measured at -24 % .. -5 % over five seeds and three axes
// (docs/design.md); it misses part of the Gauss-Markov bias, so it is low more often than high.
#include "thermodrift/features/noise_floor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "thermodrift/error.hpp"
#include "thermodrift/sim/chamber_run.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::sim {
namespace {

TEST(NoiseFloorEstimate, WithinThirtyPercentOfTheSimulatorsTrueFloor) {
  const ChamberRun run = simulate(SimulatorOptions{});
  const std::array<double, 3> truth = run.noise_floor(100.0);
  const char* const axes[] = {"gyro_x", "gyro_y", "gyro_z"};
  for (std::size_t a = 0; a < 3; ++a) {
    const NoiseFloorEstimate estimate = estimate_noise_floor(run.column("time_s"), run.column(axes[a]), 100.0);
    ASSERT_TRUE(estimate.usable());
    EXPECT_GT(estimate.differences, 40000u);  // overlapping windows: nearly one per sample
    EXPECT_NEAR(estimate.variance, truth[a], 0.3 * truth[a]) << axes[a];
  }
  // The pooled form over the log view gives the same number for one log.
  const ChamberLog log = to_chamber_log(run);
  EXPECT_DOUBLE_EQ(estimate_noise_floor({log}, 0, 100.0).variance,
                   estimate_noise_floor(run.column("time_s"), run.column("gyro_x"), 100.0).variance);
}

// The drift is what a plain Allan variance of the window means would report: ten times
// the floor on this run. The estimate must not be anywhere near that.
TEST(NoiseFloorEstimate, IgnoresTheDriftThatSwampsThePlainAllanVariance) {
  const ChamberRun run = simulate(SimulatorOptions{});
  const auto& time = run.column("time_s");
  const auto& gyro = run.column("gyro_x");
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t k = 200; k < gyro.size(); k += 100) {
    double now = 0, before = 0;
    for (std::size_t i = 0; i < 100; ++i) now += gyro[k - i], before += gyro[k - 100 - i];
    sum += (now - before) * (now - before) / 1e4 / 2;
    ++count;
  }
  const double allan = sum / static_cast<double>(count);
  const double truth = run.noise_floor(100.0)[0];
  EXPECT_GT(allan, 3 * truth);  // the premise: drift contaminates the plain estimate
  EXPECT_LT(estimate_noise_floor(time, gyro, 100.0).variance, 1.3 * truth);
}

TEST(NoiseFloorEstimate, ShortLogsGapsAndBadWindows) {
  std::vector<double> time, gyro;
  for (int i = 0; i < 250; ++i) time.push_back(i), gyro.push_back(std::sin(i));
  EXPECT_FALSE(estimate_noise_floor(time, gyro, 100.0).usable());  // under three windows
  // A gap longer than the window restarts the windows: no difference spans it.
  for (int i = 0; i < 250; ++i) time.push_back(10000 + i), gyro.push_back(std::sin(i));
  EXPECT_FALSE(estimate_noise_floor(time, gyro, 100.0).usable());
  EXPECT_THROW(estimate_noise_floor(time, gyro, 0.0), UsageError);
  gyro.pop_back();
  EXPECT_THROW(estimate_noise_floor(time, gyro, 10.0), UsageError);
}

}  // namespace
}  // namespace thermodrift::sim
