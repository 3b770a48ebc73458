#include "thermodrift/models/linear.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>
#include <utility>

#include "thermodrift/error.hpp"
#include "thermodrift/io/json_integer.hpp"

namespace thermodrift {

double Regressor::evaluate(std::span<const double> features) const {
  double value = 1.0;
  for (std::size_t i = 0; i < powers.size(); ++i) {
    for (int p = 0; p < powers[i]; ++p) value *= features[i];
  }
  return value;
}

namespace {

// A term whose own name holds '*' or '^' (a product or power term) is written in
// parentheses inside a regressor's name, so that "(lag:600^2)" and "lag:600^2" (the square
// of lag:600) read back as what they are.
std::string quoted_term(const std::string& term) {
  return term.find_first_of("*^") == std::string::npos ? term : "(" + term + ")";
}

// The factors of a regressor's name split at the '*' outside parentheses.
std::vector<std::string> top_level_factors(const std::string& text) {
  std::vector<std::string> factors(1);
  int depth = 0;
  for (const char c : text) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == '*' && depth == 0) {
      factors.emplace_back();
    } else {
      factors.back() += c;
    }
  }
  return factors;
}

}  // namespace

std::string Regressor::name(const std::vector<std::string>& term_names) const {
  std::string text;
  for (std::size_t i = 0; i < powers.size(); ++i) {
    if (powers[i] == 0) continue;
    if (!text.empty()) text += '*';
    text += quoted_term(term_names.at(i));
    if (powers[i] > 1) text += fmt::format("^{}", powers[i]);
  }
  return text;
}

Regressor Regressor::parse(const std::string& text, const std::vector<std::string>& term_names) {
  Regressor regressor{std::vector<int>(term_names.size(), 0)};
  // A regressor that is one whole term (as files written before terms were parenthesized
  // name a product or power term).
  for (std::size_t i = 0; i < term_names.size(); ++i) {
    if (term_names[i] == text) {
      regressor.powers[i] = 1;
      return regressor;
    }
  }
  for (std::string factor : top_level_factors(text)) {
    int power = 1;
    const auto close = factor.rfind(')');
    if (const auto caret = factor.rfind('^'); caret != std::string::npos && (close == std::string::npos || caret > close)) {
      try {
        power = std::stoi(factor.substr(caret + 1));
      } catch (const std::exception&) {
        throw UsageError(fmt::format("bad power in regressor '{}'", text));
      }
      if (power < 1 || power > 9) throw UsageError(fmt::format("bad power in regressor '{}'", text));
      factor.resize(caret);
    }
    if (factor.size() >= 2 && factor.front() == '(' && factor.back() == ')') factor = factor.substr(1, factor.size() - 2);
    bool known = false;
    for (std::size_t i = 0; i < term_names.size(); ++i) {
      if (term_names[i] == factor) {
        regressor.powers[i] += power;
        known = true;
      }
    }
    if (!known) throw UsageError(fmt::format("regressor '{}' names unknown term '{}'", text, factor));
  }
  return regressor;
}

std::vector<Regressor> linear_regressors(std::size_t term_count) {
  std::vector<Regressor> regressors;
  for (std::size_t i = 0; i < term_count; ++i) {
    Regressor r{std::vector<int>(term_count, 0)};
    r.powers[i] = 1;
    regressors.push_back(r);
  }
  return regressors;
}

std::vector<Regressor> quadratic_regressors(std::size_t term_count) {
  auto regressors = linear_regressors(term_count);
  for (std::size_t i = 0; i < term_count; ++i) {
    for (std::size_t j = i; j < term_count; ++j) {
      Regressor r{std::vector<int>(term_count, 0)};
      r.powers[i] += 1;
      r.powers[j] += 1;
      regressors.push_back(r);
    }
  }
  return regressors;
}

double LinearModel::predict(std::span<const double> features) const {
  double value = intercept;
  for (std::size_t k = 0; k < regressors.size(); ++k) {
    value += coefficients(static_cast<Eigen::Index>(k)) * regressors[k].evaluate(features);
  }
  return value;
}

Eigen::VectorXd LinearModel::predict(const Eigen::MatrixXd& features) const {
  // Each regressor's factors found once, not every term's power scanned on every row
  // (terms × regressors per row); multiplied in the same order, so the same bits as above.
  std::vector<std::vector<std::pair<Eigen::Index, int>>> factors(regressors.size());
  for (std::size_t k = 0; k < regressors.size(); ++k) {
    const auto& powers = regressors[k].powers;
    for (std::size_t i = 0; i < powers.size(); ++i) {
      if (powers[i] > 0) factors[k].emplace_back(static_cast<Eigen::Index>(i), powers[i]);
    }
  }
  Eigen::VectorXd out(features.rows());
  for (Eigen::Index i = 0; i < features.rows(); ++i) {
    double value = intercept;
    for (std::size_t k = 0; k < regressors.size(); ++k) {
      double regressor = 1.0;
      for (const auto& [term, power] : factors[k]) {
        for (int p = 0; p < power; ++p) regressor *= features(i, term);
      }
      value += coefficients(static_cast<Eigen::Index>(k)) * regressor;
    }
    out(i) = value;
  }
  return out;
}

nlohmann::json LinearModel::to_json(const std::vector<std::string>& term_names) const {
  nlohmann::json regressor_names = nlohmann::json::array();
  for (const auto& r : regressors) regressor_names.push_back(r.name(term_names));
  return {{"intercept", intercept},
          {"regressors", regressor_names},
          {"coefficients", std::vector<double>(coefficients.data(), coefficients.data() + coefficients.size())},
          {"rank_deficiency", rank_deficiency}};
}

LinearModel LinearModel::from_json(const nlohmann::json& json,
                                   const std::vector<std::string>& term_names) {
  LinearModel model;
  model.intercept = json.at("intercept").get<double>();
  for (const auto& name : json.at("regressors")) {
    model.regressors.push_back(Regressor::parse(name.get<std::string>(), term_names));
  }
  const auto coefficients = json.at("coefficients").get<std::vector<double>>();
  if (coefficients.size() != model.regressors.size()) {
    throw Error(fmt::format("{} coefficients for {} regressors", coefficients.size(),
                            model.regressors.size()));
  }
  model.coefficients = Eigen::Map<const Eigen::VectorXd>(coefficients.data(),
                                                         static_cast<Eigen::Index>(coefficients.size()));
  model.rank_deficiency = json.contains("rank_deficiency")
                              ? json_integer<std::size_t>(json.at("rank_deficiency"), "rank_deficiency")
                              : 0;
  return model;
}

namespace {

// A scaled column whose pivot falls below this is collinear with those before it.
constexpr double kRankThreshold = 1e-10;
// Stepwise F statistics this close (relative) are a tie.
constexpr double kTie = 1e-9;

Eigen::MatrixXd design_matrix(const Eigen::MatrixXd& features, const std::vector<Regressor>& regressors) {
  Eigen::MatrixXd design(features.rows(), static_cast<Eigen::Index>(regressors.size()) + 1);
  std::vector<double> row(static_cast<std::size_t>(features.cols()));
  for (Eigen::Index i = 0; i < features.rows(); ++i) {
    for (Eigen::Index j = 0; j < features.cols(); ++j) row[static_cast<std::size_t>(j)] = features(i, j);
    design(i, 0) = 1.0;
    for (std::size_t k = 0; k < regressors.size(); ++k) {
      design(i, static_cast<Eigen::Index>(k) + 1) = regressors[k].evaluate(row);
    }
  }
  return design;
}

}  // namespace

LinearModel fit_least_squares(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                              std::vector<Regressor> regressors) {
  const auto parameters = static_cast<Eigen::Index>(regressors.size()) + 1;
  if (features.rows() < parameters) {
    throw UsageError(fmt::format("{} samples cannot fit {} parameters", features.rows(), parameters));
  }
  const Eigen::MatrixXd design = design_matrix(features, regressors);
  // Column scaling makes the rank decision independent of the terms' units.
  const Eigen::VectorXd scale = design.colwise().norm().transpose().cwiseMax(1e-300);
  const Eigen::MatrixXd scaled = design * scale.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(scaled);
  qr.setThreshold(kRankThreshold);
  // Basic solution on the first rank() pivots, the rest left at 0. Eigen's qr.solve()
  // would not do: it keeps every pivot above machine epsilon (setThreshold affects
  // rank(), not solve()), so two collinear columns got huge cancelling coefficients.
  const Eigen::Index rank = qr.rank();
  Eigen::VectorXd rotated = target;
  rotated.applyOnTheLeft(qr.householderQ().setLength(rank).adjoint());
  Eigen::VectorXd pivoted = Eigen::VectorXd::Zero(parameters);
  pivoted.head(rank) = qr.matrixQR()
                           .topLeftCorner(rank, rank)
                           .triangularView<Eigen::Upper>()
                           .solve(rotated.head(rank));
  const Eigen::VectorXd solution = (qr.colsPermutation() * pivoted).cwiseQuotient(scale);

  LinearModel model;
  model.regressors = std::move(regressors);
  model.intercept = solution(0);
  model.coefficients = solution.tail(parameters - 1);
  model.rank_deficiency = static_cast<std::size_t>(parameters - rank);
  return model;
}

namespace {

double residual_sum_of_squares(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                               const std::vector<Regressor>& regressors) {
  const LinearModel model = fit_least_squares(features, target, regressors);
  return (target - model.predict(features)).squaredNorm();
}

// A least-squares fit seen from a candidate regressor: an orthonormal basis of its design
// (the columns fit_least_squares keeps, by the same scaled, pivoted QR and threshold) and
// its residual. With a column c added, the residual sum of squares falls by
// (c⊥·r)² / |c⊥|², c⊥ = c less its projection on the basis: one candidate costs
// rows × rank instead of a whole fit.
class Projection {
 public:
  Projection(const Eigen::MatrixXd& features, const Eigen::VectorXd& target, const std::vector<Regressor>& regressors) {
    const Eigen::MatrixXd design = design_matrix(features, regressors);
    const Eigen::VectorXd scale = design.colwise().norm().transpose().cwiseMax(1e-300);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design * scale.cwiseInverse().asDiagonal());
    qr.setThreshold(kRankThreshold);
    const Eigen::Index rank = qr.rank();
    basis_ = Eigen::MatrixXd::Identity(design.rows(), rank);
    basis_.applyOnTheLeft(qr.householderQ().setLength(rank));
    residual_ = target - basis_ * (basis_.transpose() * target);
    rss_ = residual_.squaredNorm();
  }

  double rss() const { return rss_; }

  // The residual sum of squares with `column` added; rss() when it adds no direction the
  // fit's rank test would keep.
  double rss_with(const Eigen::VectorXd& column) const {
    const Eigen::VectorXd orthogonal = column - basis_ * (basis_.transpose() * column);
    const double length = orthogonal.norm();
    if (!(length > kRankThreshold * column.norm())) return rss();
    const double along = orthogonal.dot(residual_) / length;
    return std::max(0.0, rss() - along * along);
  }

 private:
  Eigen::MatrixXd basis_;     // rows × rank, orthonormal
  Eigen::VectorXd residual_;
  double rss_ = 0;
};

}  // namespace

double cancellation(const Eigen::MatrixXd& features, const Eigen::VectorXd& coefficients, Eigen::Index grouped) {
  if (features.cols() != coefficients.size() || grouped < 0 || grouped > features.cols()) {
    throw Error("cancellation: coefficients, columns and group do not match");
  }
  if (features.rows() < 2) return 1.0;
  const auto spread = [](const Eigen::VectorXd& v) { return std::sqrt((v.array() - v.mean()).square().mean()); };
  const double whole = spread(features * coefficients);
  if (!(whole > 0)) return 1.0;
  double parts = grouped > 0 ? spread(features.leftCols(grouped) * coefficients.head(grouped)) : 0.0;
  for (Eigen::Index j = grouped; j < features.cols(); ++j) parts += spread(features.col(j) * coefficients[j]);
  return parts / whole;
}

StepwiseFit fit_stepwise(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                         const std::vector<Regressor>& candidates,
                         const std::vector<std::string>& term_names,
                         const StepwiseOptions& options) {
  if (!(options.f_to_remove < options.f_to_enter)) {
    throw UsageError("stepwise: F-to-remove must be below F-to-enter, or terms can cycle");
  }
  const auto n = static_cast<double>(features.rows());
  std::vector<bool> included(candidates.size(), false);
  auto chosen = [&](std::ptrdiff_t toggle) {
    std::vector<Regressor> out;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      const bool in = included[k] != (static_cast<std::ptrdiff_t>(k) == toggle);
      if (in) out.push_back(candidates[k]);
    }
    return out;
  };

  StepwiseFit fit;
  for (std::size_t step = 0; step < options.max_steps; ++step) {
    const auto current = chosen(-1);
    const Projection fit_now(features, target, current);
    const double rss = fit_now.rss();
    const double p = static_cast<double>(current.size());

    // Forward: the candidate with the largest partial F = (RSS - RSS+) / (RSS+ / (n - p - 2)).
    double best_f = 0;
    std::ptrdiff_t best = -1;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      if (included[k] || n - p - 2 <= 0) continue;
      options.stop.throw_if_requested("stepwise regression");
      const double rss_plus = fit_now.rss_with(design_matrix(features, {candidates[k]}).col(1));
      const double f = rss_plus > 0 ? (rss - rss_plus) / (rss_plus / (n - p - 2)) : INFINITY;
      // Ties (to rounding) go to the earlier candidate: two regressors that span the same
      // column space with the current set give the same F, and rounding must not choose.
      if (f > best_f * (1.0 + kTie)) {
        best_f = f;
        best = static_cast<std::ptrdiff_t>(k);
      }
    }
    if (best >= 0 && best_f > options.f_to_enter) {
      included[static_cast<std::size_t>(best)] = true;
      fit.path.push_back({"add", candidates[static_cast<std::size_t>(best)].name(term_names), best_f});
    } else {
      break;
    }

    // Backward: drop the included regressor with the smallest partial F if below threshold.
    const auto now = chosen(-1);
    const double rss_now = residual_sum_of_squares(features, target, now);
    const double p_now = static_cast<double>(now.size());
    double worst_f = INFINITY;
    std::ptrdiff_t worst = -1;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      if (!included[k]) continue;
      options.stop.throw_if_requested("stepwise regression");
      const double rss_minus = residual_sum_of_squares(features, target, chosen(static_cast<std::ptrdiff_t>(k)));
      const double f = rss_now > 0 ? (rss_minus - rss_now) / (rss_now / (n - p_now - 1)) : INFINITY;
      if (f < worst_f * (1.0 - kTie)) {
        worst_f = f;
        worst = static_cast<std::ptrdiff_t>(k);
      }
    }
    if (worst >= 0 && worst_f < options.f_to_remove) {
      included[static_cast<std::size_t>(worst)] = false;
      fit.path.push_back({"remove", candidates[static_cast<std::size_t>(worst)].name(term_names), worst_f});
    }
  }
  fit.model = fit_least_squares(features, target, chosen(-1));
  return fit;
}

}  // namespace thermodrift
