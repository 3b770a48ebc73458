// The causal Hampel filter: isolated spikes replaced by the median before them; noise,
// quantized signals and lasting steps left alone (a step only delayed).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "thermodrift/io/despike.hpp"

namespace thermodrift {
namespace {

// Deterministic noise in [-1, 1].
double noise(int i) { return std::sin(12.9898 * i) * 43758.5453 - std::floor(std::sin(12.9898 * i) * 43758.5453) - 0.5; }

TEST(Despike, ReplacesIsolatedSpikesByTheMedianBefore) {
  Despiker filter{DespikeOptions{}};
  std::size_t replaced_count = 0;
  for (int i = 0; i < 5000; ++i) {
    const bool spike = i == 1000 || i == 2500 || i == 2501 || i == 4000;  // two single ones, a pair, one more
    const double clean = 10 + 2 * noise(i);
    bool replaced = false;
    const double out = filter.push(clean + (spike ? 100 : 0), &replaced);
    EXPECT_EQ(replaced, spike) << "sample " << i;
    if (spike) {
      EXPECT_NEAR(out, 10, 1.0) << "replaced by the window's median";
    } else {
      EXPECT_EQ(out, clean);
    }
    replaced_count += replaced;
  }
  EXPECT_EQ(replaced_count, 4u);
}

TEST(Despike, QuantizedSignalsAndStepsPass) {
  // A signal on two levels, mostly the lower: the median absolute deviation is 0, yet a
  // value one quantum off is no outlier.
  Despiker quantized{DespikeOptions{}};
  for (int i = 0; i < 2000; ++i) {
    bool replaced = true;
    quantized.push(noise(i) > 0.2 ? 0.5 : 0.0, &replaced);
    EXPECT_FALSE(replaced) << i;
  }
  // A lasting step of 50 is held back at most half a window, then passes.
  Despiker step{DespikeOptions{}};
  int held = 0;
  for (int i = 0; i < 200; ++i) {
    bool replaced = false;
    const double value = (i < 100 ? 0 : 50) + 0.1 * noise(i);
    const double out = step.push(value, &replaced);
    if (i >= 100) {
      held += replaced;
      if (i >= 100 + 16) EXPECT_EQ(out, value) << i;
    }
  }
  EXPECT_GT(held, 0);
  EXPECT_LE(held, 16);
  // A window all on one level: a change of one resolution step passes, a jump does not.
  Despiker flat{DespikeOptions{}};
  bool replaced = false;
  for (int i = 0; i < 40; ++i) flat.push(20.0, &replaced);
  flat.push(20.001, &replaced);
  EXPECT_FALSE(replaced);
  flat.push(45.0, &replaced);
  EXPECT_TRUE(replaced);
}

TEST(Despike, OptionsAreChecked) {
  std::string why;
  EXPECT_TRUE(DespikeOptions{}.IsValid(&why));
  EXPECT_FALSE((DespikeOptions{2, 6}.IsValid(&why)));
  EXPECT_NE(why.find("3 to 100000"), std::string::npos);
  EXPECT_FALSE((DespikeOptions{std::size_t(-1), 6}.IsValid(&why)));
  EXPECT_FALSE((DespikeOptions{30, 0}.IsValid(&why)));
  EXPECT_FALSE((DespikeOptions{30, NAN}.IsValid(&why)));
}

}  // namespace
}  // namespace thermodrift
