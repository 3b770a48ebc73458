#include "thermodrift/sim/options.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "thermodrift/error.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::sim {
namespace {

TEST(SimulatorOptions, DefaultsAreValid) {
  std::string error = "untouched";
  EXPECT_TRUE(SimulatorOptions{}.IsValid(&error));
  EXPECT_EQ(error, "untouched");
  EXPECT_TRUE(SimulatorOptions{}.IsValid(nullptr));
}

TEST(SimulatorOptions, DefaultAxesDiffer) {
  const auto axes = default_simulated_axes();
  EXPECT_NE(axes[0].coil_time_constant_s, axes[1].coil_time_constant_s);
  EXPECT_NE(axes[1].coil_time_constant_s, axes[2].coil_time_constant_s);
  // Opposite signs of the temperature coefficient: no single law fits all three.
  EXPECT_LT(axes[0].temperature_dph_per_c * axes[1].temperature_dph_per_c, 0.0);
}

struct BadOption {
  const char* name;
  std::function<void(SimulatorOptions&)> spoil;
  const char* expected_in_message;
};

class SimulatorOptionsRejects : public ::testing::TestWithParam<BadOption> {};

TEST_P(SimulatorOptionsRejects, WithAReasonAndSimulateThrows) {
  SimulatorOptions options;
  GetParam().spoil(options);
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find(GetParam().expected_in_message), std::string::npos) << error;
  EXPECT_FALSE(options.IsValid(nullptr));
  EXPECT_THROW(simulate(options), UsageError);
}

const double nan = std::numeric_limits<double>::quiet_NaN();
const double inf = std::numeric_limits<double>::infinity();

INSTANTIATE_TEST_SUITE_P(
    Cases, SimulatorOptionsRejects,
    ::testing::Values(
        BadOption{"ZeroCycles", [](SimulatorOptions& o) { o.cycles = 0; }, "cycles"},
        BadOption{"ZeroRate", [](SimulatorOptions& o) { o.rate_hz = 0.0; }, "rate_hz"},
        BadOption{"NanRate", [](SimulatorOptions& o) { o.rate_hz = nan; }, "rate_hz"},
        BadOption{"InvertedRange", [](SimulatorOptions& o) { o.chamber_min_c = 70.0; }, "chamber_min_c"},
        BadOption{"StartOutsideRange", [](SimulatorOptions& o) { o.start_temperature_c = 80.0; },
                  "start_temperature_c"},
        BadOption{"ZeroRamp", [](SimulatorOptions& o) { o.ramp_rate_c_per_min = 0.0; }, "ramp_rate"},
        BadOption{"NegativeSoak", [](SimulatorOptions& o) { o.extreme_soak_min = -1.0; }, "extreme_soak_min"},
        BadOption{"InfiniteReference", [](SimulatorOptions& o) { o.reference_temperature_c = inf; },
                  "reference_temperature_c"},
        BadOption{"ZeroCoilLag", [](SimulatorOptions& o) { o.axes[2].coil_time_constant_s = 0.0; },
                  "coil_time_constant_s"},
        BadOption{"NanCoefficient", [](SimulatorOptions& o) { o.axes[1].temperature_dph_per_c = nan; },
                  "temperature_dph_per_c"},
        BadOption{"NegativeArw", [](SimulatorOptions& o) { o.noise.angle_random_walk_deg_per_sqrt_h = -0.1; },
                  "angle_random_walk"},
        BadOption{"ZeroBiasCorrelation", [](SimulatorOptions& o) { o.noise.bias_correlation_time_s = 0.0; },
                  "bias_correlation_time_s"},
        BadOption{"NegativeQuantum", [](SimulatorOptions& o) { o.noise.quantization_arcsec = -1.0; },
                  "quantization"},
        BadOption{"TooManySamples", [](SimulatorOptions& o) { o.rate_hz = 5000.0; o.cycles = 100; }, "samples"}),
    [](const ::testing::TestParamInfo<BadOption>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace thermodrift::sim
