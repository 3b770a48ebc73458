// The trailing moving average against a brute-force mean over (t - W, t].
#include "thermodrift/features/moving_average.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace thermodrift {
namespace {

// A small deterministic generator (xorshift), so the sample times are the same everywhere.
struct Xorshift {
  std::uint64_t state = 88172645463325252ull;
  double uniform() {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  }
};

double brute_force_mean(const std::vector<double>& times, const std::vector<double>& values, std::size_t k,
                        double window) {
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i <= k; ++i) {
    if (times[i] > times[k] - window) {
      sum += values[i];
      ++count;
    }
  }
  return sum / static_cast<double>(count);
}

TEST(TrailingMean, EqualsBruteForceMeanOnIrregularTimes) {
  Xorshift random;
  std::vector<double> times, values;
  double t = 1000.0;
  for (int i = 0; i < 5000; ++i) {
    // Steps from 0.01 s to 3 s, now and then a long one.
    t += random.uniform() < 0.01 ? 20.0 + random.uniform() : 0.01 + 3.0 * random.uniform();
    times.push_back(t);
    values.push_back(100.0 * std::sin(t / 50.0) + random.uniform());
  }
  for (double window : {0.5, 7.3, 60.0}) {
    TrailingMean mean(window);
    for (std::size_t k = 0; k < times.size(); ++k) {
      const double got = mean.push(times[k], values[k]);
      const double want = brute_force_mean(times, values, k, window);
      ASSERT_NEAR(got, want, 1e-9 * (1.0 + std::abs(want))) << "window " << window << " sample " << k;
      ASSERT_DOUBLE_EQ(mean.mean(), got);
    }
  }
}

TEST(TrailingMean, SampleExactlyOneWindowOldHasLeft) {
  TrailingMean mean(2.0);
  mean.push(0.0, 10.0);
  mean.push(1.0, 20.0);
  EXPECT_DOUBLE_EQ(mean.push(2.0, 30.0), 25.0);  // (0, 2]: the sample at 0 is out
}

TEST(TrailingMean, ZeroWindowPassesEachSampleThrough) {
  TrailingMean mean(0.0);
  EXPECT_EQ(mean.push(0.0, 3.0), 3.0);
  EXPECT_EQ(mean.push(1.0, -7.0), -7.0);
  EXPECT_EQ(mean.push(1.5, 2.5), 2.5);
}

TEST(TrailingMean, FullOnceTheSamplesSpanTheWindow) {
  TrailingMean mean(10.0);
  for (int t = 0; t < 10; ++t) {
    mean.push(t, 1.0);
    EXPECT_FALSE(mean.full()) << t;
  }
  mean.push(10.0, 1.0);
  EXPECT_TRUE(mean.full());
  mean.reset();
  EXPECT_FALSE(mean.full());
  EXPECT_EQ(mean.mean(), 0.0);
  EXPECT_EQ(mean.push(50.0, 4.0), 4.0);  // nothing from before the reset
  EXPECT_FALSE(mean.full());
}

TEST(TrailingMean, StaysExactOverManySamples) {
  // A large offset with small variations is where a running sum loses digits.
  TrailingMean mean(100.0);
  double got = 0;
  for (int i = 0; i < 2'000'000; ++i) got = mean.push(i * 0.5, 1e6 + ((i % 7) - 3) * 1e-3);
  // The last 200 samples (i from 1999800 to 1999999): the mean of the pattern around them.
  double want = 0;
  for (int i = 2'000'000 - 200; i < 2'000'000; ++i) want += 1e6 + ((i % 7) - 3) * 1e-3;
  want /= 200;
  EXPECT_NEAR(got, want, 1e-9);
}

// One huge finite value (a corrupted reading that got past the file checks) took the
// other samples' digits with it when it was added (1e300 + 20 is 1e300): once it has left,
// the mean is the window's again at once, not a re-sum period later.
TEST(TrailingMean, OneHugeValueDoesNotPoisonTheMeanAfterItLeaves) {
  std::vector<double> times, values;
  for (int i = 0; i < 400; ++i) {
    times.push_back(i);
    values.push_back(i == 100 ? 1e300 : 20.0 + 0.01 * (i % 13));
  }
  for (double huge : {1e300, -1e300, 1e17}) {
    values[100] = huge;
    TrailingMean mean(30.0);
    for (std::size_t k = 0; k < times.size(); ++k) {
      const double got = mean.push(times[k], values[k]);
      if (k < 130) continue;  // the window (k - 30, k] holds the huge value
      ASSERT_NEAR(got, brute_force_mean(times, values, k, 30.0), 1e-12) << huge << " sample " << k;
    }
  }
}

}  // namespace
}  // namespace thermodrift
