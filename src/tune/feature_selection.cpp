#include "thermodrift/tune/feature_selection.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "thermodrift/error.hpp"
#include "thermodrift/models/svr_model.hpp"
#include "thermodrift/tune/calibration.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The ready, decimated samples of every term asked for so far, one column per term name:
// each new batch of terms is one streaming pass over the logs.
class ColumnCache {
 public:
  ColumnCache(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline)
      : logs_(&logs), axis_(axis), pipeline_(pipeline) {
    pipeline_.terms = {FeatureTerm(FeatureTerm::Kind::delta_t)};
    const FeatureTable table = feature_table(logs, pipeline_, axis, true);
    target_ = table.target;
    columns_["dT"] = table.features.col(0);
  }

  const Eigen::VectorXd& target() const { return target_; }

  void ensure(const std::vector<std::string>& names) {
    pipeline_.terms.clear();
    for (const auto& name : names) {
      if (!columns_.count(name)) pipeline_.terms.push_back(FeatureTerm::parse(name));
    }
    if (pipeline_.terms.empty()) return;
    const FeatureTable table = feature_table(*logs_, pipeline_, axis_, true);
    for (std::size_t j = 0; j < pipeline_.terms.size(); ++j) {
      columns_[pipeline_.terms[j].name()] = table.features.col(static_cast<Eigen::Index>(j));
    }
  }

  Eigen::MatrixXd matrix(const std::vector<std::string>& names) {
    ensure(names);
    Eigen::MatrixXd x(target_.size(), static_cast<Eigen::Index>(names.size()));
    for (std::size_t j = 0; j < names.size(); ++j) x.col(static_cast<Eigen::Index>(j)) = columns_.at(names[j]);
    return x;
  }

 private:
  const std::vector<ChamberLog>* logs_;
  std::size_t axis_;
  Pipeline pipeline_;
  Eigen::VectorXd target_;
  std::map<std::string, Eigen::VectorXd> columns_;
};

// Pooled MSE of least squares (with an intercept) over blocked folds: each block is
// predicted by the fit on the rest. Columns are scaled first so that powers of large
// values do not spoil the QR's rank decisions.
double least_squares_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, int folds) {
  const Eigen::Index n = y.size();
  Eigen::MatrixXd design(n, x.cols() + 1);
  design.col(0).setOnes();
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    const double scale = x.col(j).cwiseAbs().maxCoeff();
    design.col(j + 1) = scale > 0 ? Eigen::VectorXd(x.col(j) / scale) : Eigen::VectorXd(x.col(j));
  }
  double squared_error = 0;
  for (const SampleRange& block : blocked_folds(n, folds)) {
    const Eigen::Index train_rows = n - block.size();
    Eigen::MatrixXd a(train_rows, design.cols());
    Eigen::VectorXd b(train_rows);
    a.topRows(block.begin) = design.topRows(block.begin);
    a.bottomRows(n - block.end) = design.bottomRows(n - block.end);
    b.head(block.begin) = y.head(block.begin);
    b.tail(n - block.end) = y.tail(n - block.end);
    const Eigen::VectorXd beta = a.colPivHouseholderQr().solve(b);
    const Eigen::VectorXd residual = y.segment(block.begin, block.size()) -
                                     design.middleRows(block.begin, block.size()) * beta;
    squared_error += residual.squaredNorm();
  }
  return squared_error / static_cast<double>(n);
}

// Blocked CV MSE of an SVR at fixed options, in (°/h)², features and target standardized
// on the whole table (as the final fit does).
double svr_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const FeatureSelectionOptions& options) {
  const Standardization scaling = Standardization::of(x, y);
  SvrTuningOptions tuning;
  tuning.objective = TuneObjective::cv;
  tuning.folds = options.folds;
  tuning.solver = options.svr;
  const SvrObjective objective(scaling.features(x), scaling.target(y), tuning);
  const double sigma = std::sqrt(1.0 / (2.0 * options.svr.gamma));
  return objective(options.svr.C, sigma, options.svr.epsilon) * scaling.target_scale * scaling.target_scale;
}

// The time constants of a term's atoms.
std::vector<double> time_constants(const FeatureTerm& term) {
  std::vector<double> out;
  for (const auto& factor : term.factors) {
    if (factor.atom.tau > 0) out.push_back(factor.atom.tau);
    if (factor.atom.tau2 > 0) out.push_back(factor.atom.tau2);
  }
  return out;
}

// `terms` with every time constant equal to `from` set to `to`.
std::vector<std::string> with_time_constant(const std::vector<std::string>& terms, double from, double to) {
  std::vector<std::string> out;
  for (const auto& name : terms) {
    FeatureTerm term = FeatureTerm::parse(name);
    for (auto& factor : term.factors) {
      if (factor.atom.tau == from) factor.atom.tau = to;
      if (factor.atom.tau2 == from) factor.atom.tau2 = to;
    }
    out.push_back(term.name());
  }
  return out;
}

// Terms worth offering once `chosen` holds a lag of TAU: the gradient's rate behind the
// coil's (gradrate:TAU:TG) and a heating/cooling memory of the coil's rate (dir:TD:TAU).
std::vector<std::string> conditional_candidates(const std::vector<std::string>& chosen) {
  std::set<double> lags;
  for (const auto& name : chosen) {
    const FeatureTerm term = FeatureTerm::parse(name);
    for (const auto& factor : term.factors) {
      if (factor.atom.kind == FeatureAtom::Kind::lag || factor.atom.kind == FeatureAtom::Kind::lag_rate) {
        lags.insert(factor.atom.tau);
      }
    }
  }
  std::vector<std::string> out;
  for (const double tau : lags) {
    for (const double tg : time_constant_grid()) {
      if (tg <= 1920) out.push_back(fmt::format("gradrate:{}:{}", tau, tg));
    }
    for (const double td : {300.0, 900.0, 2700.0}) out.push_back(fmt::format("dir:{}:{}", td, tau));
    out.push_back(fmt::format("lag:{}*lagrate:{}", tau, tau));
  }
  return out;
}

}  // namespace

std::vector<double> time_constant_grid() {
  std::vector<double> grid;
  for (int k = 0; k <= 12; ++k) grid.push_back(std::round(60.0 * std::pow(std::sqrt(2.0), k)));
  return grid;
}

std::vector<std::string> base_candidate_terms() {
  std::vector<std::string> out = {"dT", "rate", "dT^2", "dT*rate", "dir:300", "dir:900", "dir:2700"};
  for (const double tau : time_constant_grid()) {
    out.push_back(fmt::format("lag:{}", tau));
    out.push_back(fmt::format("lag:{}^2", tau));
    out.push_back(fmt::format("lagrate:{}", tau));
  }
  return out;
}

nlohmann::json FeatureSelection::to_json(const FeatureSelectionOptions& options) const {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& step : path) {
    steps.push_back({{"action", step.action}, {"term", step.term}, {"cv_mse", step.cv_mse}, {"terms", step.terms}});
  }
  return {{"scored_by", options.model == "svr" ? "svr" : "least_squares"},
          {"folds", options.folds},
          {"min_gain", options.min_gain},
          {"start_mse", start_mse},
          {"cv_mse", cv_mse},
          {"candidates_scored", candidates_scored},
          {"terms", terms},
          {"path", steps}};
}

FeatureSelection select_features(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline,
                                 const FeatureSelectionOptions& options) {
  ColumnCache cache(logs, axis, pipeline);
  const Eigen::VectorXd& y = cache.target();
  if (y.size() < 4 * options.folds) {
    throw UsageError(fmt::format("--features auto: {} samples are too few for {}-fold selection", y.size(),
                                 options.folds));
  }
  const bool by_svr = options.model == "svr";
  FeatureSelection result;
  auto least_squares = [&](const std::vector<std::string>& terms) {
    ++result.candidates_scored;
    return least_squares_cv(cache.matrix(terms), y, options.folds);
  };
  auto score = [&](const std::vector<std::string>& terms) {
    if (!by_svr) return least_squares(terms);
    ++result.candidates_scored;
    return svr_cv(cache.matrix(terms), y, options);
  };
  std::vector<std::string> chosen;
  double current = least_squares_cv(Eigen::MatrixXd(y.size(), 0), y, options.folds);
  result.start_mse = current;
  // A candidate is one term or a block of terms sharing one lag (the coil's temperature
  // and its rate enter together); a block of k terms must pay k penalties.
  std::vector<std::vector<std::string>> candidates;
  for (const auto& term : base_candidate_terms()) candidates.push_back({term});
  for (const double tau : time_constant_grid()) {
    candidates.push_back({fmt::format("lag:{}", tau), fmt::format("lagrate:{}", tau)});
    candidates.push_back({fmt::format("lag:{}", tau), fmt::format("lagrate:{}", tau), fmt::format("lag:{}^2", tau)});
  }
  for (const auto& block : candidates) cache.ensure(block);
  const double keep = 1.0 - options.min_gain;
  auto is_chosen = [&](const std::string& term) { return std::find(chosen.begin(), chosen.end(), term) != chosen.end(); };
  auto with_block = [&](const std::vector<std::string>& block) {
    std::vector<std::string> terms = chosen;
    for (const auto& term : block) {
      if (std::find(terms.begin(), terms.end(), term) == terms.end()) terms.push_back(term);
    }
    return terms;
  };

  // Forward steps: the candidate whose penalized score (CV MSE / keep^k for k new terms)
  // is lowest, while it beats the current score.
  while (chosen.size() < options.max_terms) {
    std::vector<std::pair<double, std::size_t>> ranked;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const auto terms = with_block(candidates[c]);
      const std::size_t added = terms.size() - chosen.size();
      if (added == 0 || terms.size() > options.max_terms) continue;
      ranked.emplace_back(least_squares(terms) / std::pow(keep, static_cast<double>(added)), c);
    }
    if (ranked.empty()) break;
    std::stable_sort(ranked.begin(), ranked.end());
    double best = kInfinity, best_penalized = kInfinity;
    std::size_t best_candidate = ranked.front().second;
    const std::size_t scored = by_svr ? std::min(ranked.size(), std::max<std::size_t>(options.shortlist, 1)) : 1;
    for (std::size_t i = 0; i < scored; ++i) {
      const auto terms = with_block(candidates[ranked[i].second]);
      const double value = by_svr ? score(terms) : ranked[i].first * std::pow(keep, double(terms.size() - chosen.size()));
      const double penalized = value / std::pow(keep, static_cast<double>(terms.size() - chosen.size()));
      if (penalized < best_penalized) best = value, best_penalized = penalized, best_candidate = ranked[i].second;
    }
    if (!(best_penalized < current)) break;
    const auto& block = candidates[best_candidate];
    std::string added;
    for (const auto& term : block) {
      if (!is_chosen(term)) added += (added.empty() ? "" : ",") + term;
    }
    chosen = with_block(block);
    current = best;
    result.path.push_back({"add", added, current, chosen});
    for (const auto& term : conditional_candidates(chosen)) {
      const std::vector<std::string> single{term};
      if (std::find(candidates.begin(), candidates.end(), single) == candidates.end()) candidates.push_back(single);
    }
  }
  if (by_svr && !chosen.empty()) current = score(chosen);

  // Each distinct time constant moves (all its uses together: one physical lag) by
  // factors 2^(±1/4), then 2^(±1/8), 2^(±1/16), while that pays.
  auto tune_time_constants = [&] {
    for (const double step : {0.25, 0.125, 0.0625}) {
      std::set<double> constants;
      for (const auto& name : chosen) {
        for (double tau : time_constants(FeatureTerm::parse(name))) constants.insert(tau);
      }
      for (double tau : constants) {
        for (bool improved = true; improved;) {
          improved = false;
          for (const double factor : {std::pow(2.0, step), std::pow(2.0, -step)}) {
            const double moved = std::round(tau * factor);
            if (moved == tau || moved < 1 || constants.count(moved)) continue;
            const auto trial = with_time_constant(chosen, tau, moved);
            const double value = score(trial);
            if (value < current) {
              result.path.push_back({"tune", fmt::format("{} -> {}", tau, moved), value, trial});
              chosen = trial;
              current = value;
              tau = moved;
              improved = true;
              break;
            }
          }
        }
      }
    }
  };
  tune_time_constants();

  // Backward steps: a term whose removal costs less than its penalty goes (a proxy taken
  // early that later terms made redundant).
  for (bool removed = true; removed && chosen.size() > 1;) {
    removed = false;
    double best = kInfinity;
    std::size_t best_index = 0;
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      std::vector<std::string> trial = chosen;
      trial.erase(trial.begin() + static_cast<std::ptrdiff_t>(i));
      const double value = score(trial);
      if (value < best) best = value, best_index = i;
    }
    if (best * keep < current) {
      const std::string term = chosen[best_index];
      chosen.erase(chosen.begin() + static_cast<std::ptrdiff_t>(best_index));
      current = best;
      result.path.push_back({"drop", term, current, chosen});
      removed = true;
    }
  }
  if (!result.path.empty() && result.path.back().action == "drop") tune_time_constants();
  if (chosen.empty()) chosen = {"dT", "rate"};  // nothing pays: the seed's pair
  result.terms = chosen;
  result.cv_mse = current;
  return result;
}

}  // namespace thermodrift
