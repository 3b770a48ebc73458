#include "thermodrift/models/metrics.hpp"

namespace thermodrift {

nlohmann::json ResidualMetrics::to_json() const {
  return {{"samples", samples},
          {"mse_before", mse_before},
          {"mse_after", mse_after},
          {"residual_std", residual_std},
          {"residual_peak_to_peak", residual_peak_to_peak}};
}

ResidualMetrics residual_metrics(const Eigen::VectorXd& target, const Eigen::VectorXd& prediction) {
  ResidualMetrics metrics;
  metrics.samples = static_cast<std::size_t>(target.size());
  if (target.size() == 0) return metrics;
  const auto n = static_cast<double>(target.size());
  const Eigen::VectorXd residual = target - prediction;
  metrics.mse_before = (target.array() - target.mean()).square().sum() / n;
  metrics.mse_after = residual.squaredNorm() / n;
  metrics.residual_std = std::sqrt((residual.array() - residual.mean()).square().sum() / n);
  metrics.residual_peak_to_peak = residual.maxCoeff() - residual.minCoeff();
  return metrics;
}

}  // namespace thermodrift
