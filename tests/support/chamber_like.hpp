// Chamber-like ε-SVR data, shared by the libsvm reference tests and bench/svr_bench: the
// features ΔT and dT/dt of a sensor lagging a chamber cycle, a smooth nonlinear drift plus
// noise, features and target standardized.
#pragma once

#include <Eigen/Dense>

#include <cmath>
#include <random>

namespace thermodrift::testing {

struct SvrData {
  Eigen::MatrixXd samples;
  Eigen::VectorXd targets;
};

inline double sample_standard_deviation(const Eigen::VectorXd& values) {
  const double mean = values.mean();
  return std::sqrt((values.array() - mean).square().sum() / static_cast<double>(values.size() - 1));
}

// Each feature column and the target to mean 0 and sample standard deviation 1.
inline void standardize(SvrData& data) {
  for (Eigen::Index c = 0; c < data.samples.cols(); ++c) {
    Eigen::VectorXd column = data.samples.col(c);
    data.samples.col(c) = (column.array() - column.mean()) / sample_standard_deviation(column);
  }
  data.targets = (data.targets.array() - data.targets.mean()) / sample_standard_deviation(data.targets);
}

// Chamber cycles -40..60 °C at ±1 °C/min with 30 min soaks, seen by a sensor lagging
// 300 s, one sample per 10 s (a 100 s mean decimated); noise `noise_level` of the drift's
// scale before standardizing.
inline SvrData chamber_like(int count, unsigned seed, double noise_level = 0.1) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double ramp = 6000, soak = 1800, period = 2 * (ramp + soak);
  auto chamber = [&](double t) {
    const double phase = std::fmod(t, period);
    if (phase < ramp) return -40 + 100 * phase / ramp;
    if (phase < ramp + soak) return 60.0;
    if (phase < 2 * ramp + soak) return 60 - 100 * (phase - ramp - soak) / ramp;
    return -40.0;
  };
  SvrData data{Eigen::MatrixXd(count, 2), Eigen::VectorXd(count)};
  double sensor = -40, previous = -40, time = 0;
  for (int i = 0; i < count; ++i) {
    for (int second = 0; second < 10; ++second, time += 1) sensor += (chamber(time) - sensor) / 300;
    const double rate = (sensor - previous) / 10 * 60;
    previous = sensor;
    const double delta = sensor - 20;
    data.samples(i, 0) = delta;
    data.samples(i, 1) = rate;
    data.targets(i) = 0.02 * delta + 0.5 * std::tanh(1.5 * rate) +
                      0.3 * std::exp(-std::pow((delta - 10) / 25, 2)) + 0.15 * rate * delta / 50 +
                      noise_level * noise(generator);
  }
  standardize(data);
  return data;
}

}  // namespace thermodrift::testing
