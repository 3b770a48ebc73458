// An ε-SVR drift model as stored in the model file: the RBF decision function, trained
// on standardized features and target, plus the standardization that maps a sample's
// features in and the prediction out. Users never choose a scale by hand.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "thermodrift/models/fit_record.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/models/svr_reduce.hpp"

namespace thermodrift {

// The smallest scale a standardization has: a spread below it counts as constant. A model
// file's scales are refused below it, since features are divided by them (a subnormal
// scale made every prediction NaN); the numbers divided stay within ±1e12, the quotients
// within 1e24.
inline constexpr double kMinStandardScale = 1e-12;

// Affine map of each feature to zero mean and unit standard deviation (features whose
// spread is at most kMinStandardScale keep scale 1 rather than dividing by almost zero).
struct Standardization {
  Eigen::VectorXd feature_mean;
  Eigen::VectorXd feature_scale;
  double target_mean = 0;
  double target_scale = 1;

  static Standardization of(const Eigen::MatrixXd& features, const Eigen::VectorXd& target);
  static Standardization identity(Eigen::Index feature_count);
  Eigen::MatrixXd features(const Eigen::MatrixXd& raw) const;
  Eigen::VectorXd target(const Eigen::VectorXd& raw) const;
};

struct SvrModel {
  Standardization scaling;
  RbfDecisionFunction function;  // in standardized units
  double C = 0;                  // hyper-parameters it was trained with (informational)
  double epsilon = 0;            // in standardized target units
  bool converged = true;
  // Partially linear: a least-squares part in the raw features, the RBF SVR fitted to its
  // residual. The linear part carries what must extrapolate (rates and memories of other
  // programmes); the kernel, which reverts to its mean away from its data, only corrects.
  std::optional<LinearModel> linear_part;

  double sigma() const;  // RBF width in standardized feature units: gamma = 1/(2 sigma²)
  // One sample, as the field predicts (the Compensator): RbfDecisionFunction::fast.
  double predict(std::span<const double> features) const;
  // One row per sample, the same bits on every x86-64 (fit's figures, evaluate, report).
  Eigen::VectorXd predict(const Eigen::MatrixXd& features) const;

  nlohmann::json to_json(const std::vector<std::string>& term_names) const;
  // Throws Error when sizes disagree with `term_names` or a number is not finite.
  static SvrModel from_json(const nlohmann::json& json, const std::vector<std::string>& term_names);
};

// Replaces the model's decision function by its reduced set (models/svr_reduce.hpp) fitted
// at `scaled_points` (standardized features, one sample per row) and returns the record of
// it the axis' fit keeps (FitRecord::compressed): vectors before and after, and the change
// of the prediction at those points in the target's units (°/h). A model within the budget
// is left as it is.
CompressionRecord compress(SvrModel& model, const Eigen::MatrixXd& scaled_points, const ReduceOptions& options);

}  // namespace thermodrift
