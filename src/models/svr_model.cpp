#include "thermodrift/models/svr_model.hpp"

#include <fmt/format.h>

#include <cmath>

#include "thermodrift/error.hpp"

namespace thermodrift {

Standardization Standardization::of(const Eigen::MatrixXd& features, const Eigen::VectorXd& target) {
  Standardization s;
  const auto n = static_cast<double>(features.rows());
  s.feature_mean = features.colwise().mean().transpose();
  s.feature_scale.resize(features.cols());
  for (Eigen::Index j = 0; j < features.cols(); ++j) {
    const double sd = std::sqrt((features.col(j).array() - s.feature_mean(j)).square().sum() / n);
    s.feature_scale(j) = sd > kMinStandardScale ? sd : 1.0;
  }
  s.target_mean = target.mean();
  const double sd = std::sqrt((target.array() - s.target_mean).square().sum() / n);
  s.target_scale = sd > kMinStandardScale ? sd : 1.0;
  return s;
}

Standardization Standardization::identity(Eigen::Index feature_count) {
  Standardization s;
  s.feature_mean = Eigen::VectorXd::Zero(feature_count);
  s.feature_scale = Eigen::VectorXd::Ones(feature_count);
  return s;
}

Eigen::MatrixXd Standardization::features(const Eigen::MatrixXd& raw) const {
  return (raw.rowwise() - feature_mean.transpose()).array().rowwise() /
         feature_scale.transpose().array();
}

Eigen::VectorXd Standardization::target(const Eigen::VectorXd& raw) const {
  return (raw.array() - target_mean) / target_scale;
}

CompressionRecord compress(SvrModel& model, const Eigen::MatrixXd& scaled_points, const ReduceOptions& options) {
  const ReducedSet reduced = reduce_rbf(model.function, scaled_points, options);
  model.function = reduced.function;
  const double scale = model.scaling.target_scale;
  CompressionRecord record;
  record.method = "kernel matching pursuit, least squares at the points";
  record.from_vectors = reduced.original_vectors;
  record.to_vectors = static_cast<std::size_t>(reduced.function.support_vectors.rows());
  record.points = reduced.points;
  record.rms_change = reduced.rms_change * scale;
  record.max_change = reduced.max_change * scale;
  return record;
}

double SvrModel::sigma() const { return sigma_of_gamma(function.gamma); }

double SvrModel::predict(std::span<const double> features) const {
  // Few features (2-10): a small fixed buffer keeps prediction free of allocation.
  constexpr std::size_t kMaxStack = 32;
  double scaled[kMaxStack];
  std::vector<double> heap;
  double* x = scaled;
  if (features.size() > kMaxStack) {
    heap.resize(features.size());
    x = heap.data();
  }
  for (std::size_t j = 0; j < features.size(); ++j) {
    const auto k = static_cast<Eigen::Index>(j);
    x[j] = (features[j] - scaling.feature_mean(k)) / scaling.feature_scale(k);
  }
  const double kernel_part = function.fast(x) * scaling.target_scale + scaling.target_mean;
  return linear_part ? kernel_part + linear_part->predict(features) : kernel_part;
}

Eigen::VectorXd SvrModel::predict(const Eigen::MatrixXd& features) const {
  Eigen::VectorXd kernel_part =
      (function.predict(scaling.features(features)).array() * scaling.target_scale + scaling.target_mean).matrix();
  if (linear_part) kernel_part += linear_part->predict(features);
  return kernel_part;
}

namespace {
std::vector<double> as_vector(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

Eigen::VectorXd as_eigen(const nlohmann::json& json, std::size_t expected, const char* what) {
  const auto values = json.get<std::vector<double>>();
  if (values.size() != expected) {
    throw Error(fmt::format("{} has {} values, expected {}", what, values.size(), expected));
  }
  Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  if (!v.allFinite()) throw Error(fmt::format("{} holds a non-finite number", what));
  return v;
}
}  // namespace

nlohmann::json SvrModel::to_json(const std::vector<std::string>& term_names) const {
  nlohmann::json support_vectors = nlohmann::json::array();
  for (Eigen::Index i = 0; i < function.support_vectors.rows(); ++i) {
    support_vectors.push_back(as_vector(function.support_vectors.row(i).transpose()));
  }
  nlohmann::json json = {{"terms", term_names},
          {"feature_mean", as_vector(scaling.feature_mean)},
          {"feature_scale", as_vector(scaling.feature_scale)},
          {"target_mean", scaling.target_mean},
          {"target_scale", scaling.target_scale},
          {"kernel", "rbf"},
          {"gamma", function.gamma},
          {"sigma", sigma()},
          {"C", C},
          {"epsilon", epsilon},
          {"converged", converged},
          {"bias", function.bias},
          {"coefficients", as_vector(function.coefficients)},
          {"support_vectors", support_vectors}};
  if (linear_part) json["linear_part"] = linear_part->to_json(term_names);
  return json;
}

SvrModel SvrModel::from_json(const nlohmann::json& json, const std::vector<std::string>& term_names) {
  const std::size_t d = term_names.size();
  if (json.at("terms").get<std::vector<std::string>>() != term_names) {
    throw Error("SVR model terms differ from the pipeline's");
  }
  if (json.at("kernel").get<std::string>() != "rbf") throw Error("only the rbf kernel is supported");
  SvrModel model;
  model.scaling.feature_mean = as_eigen(json.at("feature_mean"), d, "feature_mean");
  model.scaling.feature_scale = as_eigen(json.at("feature_scale"), d, "feature_scale");
  for (Eigen::Index j = 0; j < model.scaling.feature_scale.size(); ++j) {
    if (!(model.scaling.feature_scale(j) >= kMinStandardScale)) {
      throw Error(fmt::format("model.feature_scale[{}] is {:.6g}: a scale must be at least {:g} (features are divided "
                              "by it)", j, model.scaling.feature_scale(j), kMinStandardScale));
    }
  }
  model.scaling.target_mean = json.at("target_mean").get<double>();
  model.scaling.target_scale = json.at("target_scale").get<double>();
  model.function.gamma = json.at("gamma").get<double>();
  model.function.bias = json.at("bias").get<double>();
  model.C = json.at("C").get<double>();
  model.epsilon = json.at("epsilon").get<double>();
  model.converged = json.value("converged", true);
  for (double v : {model.scaling.target_mean, model.scaling.target_scale, model.function.gamma,
                   model.function.bias}) {
    if (!std::isfinite(v)) throw Error("non-finite number in the SVR model");
  }
  if (!(model.function.gamma > 0)) throw Error("gamma must be positive");
  // σ = √(1/(2γ)) divides by γ: a subnormal γ made σ infinite.
  if (!std::isfinite(model.sigma())) {
    throw Error(fmt::format("gamma {:.6g} is too small: sigma = sqrt(1/(2 gamma)) is not finite", model.function.gamma));
  }
  // Predictions are target_mean + target_scale·f(x): a scale of 0 makes every one the mean,
  // and a standardized target is divided by it.
  if (!(model.scaling.target_scale >= kMinStandardScale)) {
    throw Error(fmt::format("target_scale must be positive, at least {:g}, not {:.6g}", kMinStandardScale,
                            model.scaling.target_scale));
  }
  // sigma is written for people beside gamma = 1/(2 sigma²); an edit of one alone leaves
  // a file whose reader cannot tell which was meant.
  if (json.contains("sigma")) {
    const double sigma = json.at("sigma").get<double>();
    if (!(std::abs(sigma - model.sigma()) <= 1e-9 * model.sigma())) {
      throw Error(fmt::format("sigma {} disagrees with gamma {} (sigma = {:.17g})", sigma, model.function.gamma,
                              model.sigma()));
    }
  }
  const auto& support_vectors = json.at("support_vectors");
  const std::size_t n = support_vectors.size();
  model.function.coefficients = as_eigen(json.at("coefficients"), n, "coefficients");
  model.function.support_vectors.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(d));
  for (std::size_t i = 0; i < n; ++i) {
    model.function.support_vectors.row(static_cast<Eigen::Index>(i)) =
        as_eigen(support_vectors[i], d, "support vector").transpose();
  }
  if (json.contains("linear_part")) model.linear_part = LinearModel::from_json(json.at("linear_part"), term_names);
  return model;
}

}  // namespace thermodrift
