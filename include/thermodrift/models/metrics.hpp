// Residual metrics of a drift model on smoothed data, in (°/h)² and °/h.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>

#include <Eigen/Dense>

namespace thermodrift {

struct ResidualMetrics {
  std::size_t samples = 0;
  double mse_before = 0;             // variance of the smoothed drift (what a constant bias leaves)
  double mse_after = 0;              // mean square of smoothed drift - prediction
  double residual_std = 0;           // standard deviation of that residual
  double residual_peak_to_peak = 0;  // max - min of that residual

  nlohmann::json to_json() const;
};

// Metrics of `prediction` against the smoothed drift `target`.
ResidualMetrics residual_metrics(const Eigen::VectorXd& target, const Eigen::VectorXd& prediction);

}  // namespace thermodrift
