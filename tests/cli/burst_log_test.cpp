// A burst log straight from its raw file (issue 14): time in ms, temperature in raw
// counts, gyro in rad/s with a driver error of x2, 5 s bursts every 5 min. Each burst's
// mean is one sample, so a linear fit on dT gives the slope of the least-squares line
// through the burst means.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"

namespace thermodrift::testing {
namespace {

constexpr double kSlope = 0.037;  // °/h per °C
constexpr double kPeriod = 300, kStep = 0.1;
constexpr int kBursts = 60, kPerBurst = 50;

// Chamber temperature: a triangle from 20 °C to 50, down to -10 and back, 1 °C/min.
double temperature(double t) {
  const double minutes = std::fmod(t / 60, 120);
  if (minutes < 30) return 20 + minutes;
  if (minutes < 90) return 50 - (minutes - 30);
  return -10 + (minutes - 90);
}

struct BurstLog {
  std::string raw;                      // the file as logged
  std::vector<double> mean_t, mean_g;   // each burst's mean temperature (°C) and gyro (°/h)
};

BurstLog make_burst_log() {
  BurstLog log;
  log.raw = "time_ms,temp_raw,gyro_radps\n";
  const double to_radps = std::numbers::pi / 180 / 3600;
  for (int b = 0; b < kBursts; ++b) {
    double sum_t = 0, sum_g = 0;
    for (int k = 0; k < kPerBurst; ++k) {
      const double t = b * kPeriod + k * kStep;
      const long counts = std::lround((temperature(t) + 231) * 256);  // 256 counts per °C, offset 231 °C
      const double celsius = counts / 256.0 - 231;
      const double noise = 0.3 * std::sin(12.9898 * (b * kPerBurst + k));  // deterministic, zero-mean-ish
      const double dph = 0.4 + kSlope * (celsius - 20) + noise;
      log.raw += fmt::format("{},{},{:.12g}\n", std::llround(t * 1000), counts, 2 * dph * to_radps);  // driver error x2
      sum_t += celsius;
      sum_g += dph;
    }
    log.mean_t.push_back(sum_t / kPerBurst);
    log.mean_g.push_back(sum_g / kPerBurst);
  }
  return log;
}

// Least-squares slope of y on x over [first, end).
double slope(const std::vector<double>& x, const std::vector<double>& y, std::size_t first) {
  double mx = 0, my = 0;
  const double n = static_cast<double>(x.size() - first);
  for (std::size_t i = first; i < x.size(); ++i) mx += x[i] / n, my += y[i] / n;
  double sxy = 0, sxx = 0;
  for (std::size_t i = first; i < x.size(); ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxy / sxx;
}

// The command: columns found by name (time_ms, temp_raw, gyro_radps).
const std::string kRawOptions =
    "--time-unit ms --gyro-unit radps --gyro-scale 0.5 --temp-scale 0.00390625 --temp-offset -231";

TEST(BurstLog, FitsFromTheRawFileWithTheSlopeOfTheBurstMeans) {
  TempDir dir;
  const BurstLog log = make_burst_log();
  dir.write("burst.csv", log.raw);
  const auto fit = run_thermodrift(dir, "fit --data burst.csv " + kRawOptions + " --features dT --model linear --out m.json");
  ASSERT_EQ(fit.status, 0) << fit.err;
  EXPECT_NE(fit.err.find("burst log, 60 bursts of 50 samples (4.9 s) every 300 s"), std::string::npos) << fit.err;
  EXPECT_NE(fit.out.find("samples: 3000 rows in 1 log(s) -> 60 burst means -> 59 ready"), std::string::npos) << fit.out;
  const auto model = nlohmann::json::parse(read_file(dir.file("m.json")));
  const double fitted = model["axes"][0]["model"]["coefficients"][0].get<double>();
  // The first burst is the warm-up; the line through the other burst means, and the truth.
  EXPECT_NEAR(fitted, slope(log.mean_t, log.mean_g, 1), 1e-6);
  EXPECT_NEAR(fitted, kSlope, 0.03 * kSlope);

  // compensate streams the raw rows with the model alone: only the first burst warms up.
  const auto compensated = run_thermodrift(dir, "compensate --model m.json --data burst.csv --out c.csv");
  ASSERT_EQ(compensated.status, 0) << compensated.err;
  EXPECT_NE(compensated.err.find("50 of 3000 rows not ready"), std::string::npos) << compensated.err;
  const auto lines = split_lines(read_file(dir.file("c.csv")));
  ASSERT_EQ(lines.size(), 3001u);
  // evaluate on the same file: the burst means, as fit saw them.
  const auto evaluated = run_thermodrift(dir, "evaluate --model m.json --data burst.csv --json");
  ASSERT_EQ(evaluated.status, 0) << evaluated.err;
  EXPECT_EQ(nlohmann::json::parse(evaluated.out)["axes"][0]["samples"], 59);
}

}  // namespace
}  // namespace thermodrift::testing
