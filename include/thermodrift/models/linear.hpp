// Linear-in-parameters drift models: ordinary least squares by QR and stepwise
// regression (the paper's reference baseline), each with an intercept.
#pragma once

#include <nlohmann/json.hpp>

#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "thermodrift/stop_token.hpp"

namespace thermodrift {

// A regressor is a product of powers of the pipeline's terms: "dT", "dT^2", "dT*rate".
struct Regressor {
  std::vector<int> powers;  // one exponent per pipeline term

  double evaluate(std::span<const double> features) const;
  std::string name(const std::vector<std::string>& term_names) const;
  // Parses a name made by name(); UsageError when it names an unknown term.
  static Regressor parse(const std::string& text, const std::vector<std::string>& term_names);
};

// Each term alone: the plain linear model of the paper's comparison.
std::vector<Regressor> linear_regressors(std::size_t term_count);
// Terms, their squares and pairwise products: the stepwise candidate set
// (for the paper's pair: dT, rate, dT², rate², dT·rate).
std::vector<Regressor> quadratic_regressors(std::size_t term_count);

struct LinearModel {
  std::vector<Regressor> regressors;
  Eigen::VectorXd coefficients;  // one per regressor
  double intercept = 0;
  std::size_t rank_deficiency = 0;  // regressors left at 0 because collinear with others

  double predict(std::span<const double> features) const;
  Eigen::VectorXd predict(const Eigen::MatrixXd& features) const;  // one row per sample

  nlohmann::json to_json(const std::vector<std::string>& term_names) const;
  static LinearModel from_json(const nlohmann::json& json, const std::vector<std::string>& term_names);
};

// Least squares with an intercept, solved by column-pivoting Householder QR (never the
// normal equations: dT² and dT·rate are strongly collinear with dT). Collinear
// regressors (a constant temperature makes dT collinear with the intercept) get
// coefficient 0 and are counted in rank_deficiency. Throws UsageError with fewer
// samples than parameters.
LinearModel fit_least_squares(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                              std::vector<Regressor> regressors);

// How much the parts of a linear fit cancel on the rows of `features`: the sum of the
// spreads (standard deviations) of the parts' contributions over the spread of their sum,
// Σ_p sd(X_p·β_p) / sd(X·β). The first `grouped` columns are one part (a static map
// and its hinges, whose contributions cancel by design), every other column a part of its
// own. About 1 when the parts add up; large when the fit is a small difference of large
// terms, which any mismatch of one part (a state started elsewhere, another excitation)
// turns into a large error. 1 for a constant fit.
double cancellation(const Eigen::MatrixXd& features, const Eigen::VectorXd& coefficients, Eigen::Index grouped);

struct StepwiseOptions {
  double f_to_enter = 4.0;   // partial F a candidate needs to enter (Efroymson's classical value)
  double f_to_remove = 3.9;  // partial F below which an included regressor leaves; < f_to_enter avoids cycling
  std::size_t max_steps = 50;  // bound on add/remove steps
  StopToken stop;              // asked before every candidate's fit (Interrupted)
};

struct StepwiseStep {
  std::string action;     // "add" or "remove"
  std::string regressor;
  double f_statistic;
};

struct StepwiseFit {
  LinearModel model;
  std::vector<StepwiseStep> path;
};

// Efroymson's forward-backward stepwise regression from `candidates` by partial F tests.
// Note: on autocorrelated logs the F test is liberal (samples are not independent); the
// held-out error, not the F statistic, is what to judge the result by.
// `term_names` only label the path.
StepwiseFit fit_stepwise(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                         const std::vector<Regressor>& candidates,
                         const std::vector<std::string>& term_names,
                         const StepwiseOptions& options = {});

}  // namespace thermodrift
