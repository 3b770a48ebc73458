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
#include "tune/term_columns.hpp"

namespace thermodrift {

namespace {

using Terms = std::vector<std::string>;

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

// Candidates offered once `chosen` holds a lag of TAU: the gradient's rate behind the
// coil's (gradrate:TAU:TG), a heating/cooling memory of the coil's rate (dir:TD:TAU) and
// lag*lagrate; each alone, and two of different kinds together. Pairs matter: a Shupe term
// and a hysteresis term often pay only together, and alone each is beaten by moving the
// lag itself, which the greedy search then cannot undo.
std::vector<Terms> conditional_candidates(const Terms& chosen) {
  std::set<double> lags;
  for (const auto& name : chosen) {
    const FeatureTerm term = FeatureTerm::parse(name);
    for (const auto& factor : term.factors) {
      if (factor.atom.kind == FeatureAtom::Kind::lag || factor.atom.kind == FeatureAtom::Kind::lag_rate) {
        lags.insert(factor.atom.tau);
      }
    }
  }
  std::vector<Terms> out;
  for (const double tau : lags) {
    std::vector<Terms> kinds(3);
    for (const double tg : time_constant_grid()) {
      if (tg <= 1920) kinds[0].push_back(fmt::format("gradrate:{}:{}", tau, tg));
    }
    for (const double td : {300.0, 900.0, 2700.0}) kinds[1].push_back(fmt::format("dir:{}:{}", td, tau));
    kinds[2].push_back(fmt::format("lag:{}*lagrate:{}", tau, tau));
    for (std::size_t k = 0; k < kinds.size(); ++k) {
      for (const auto& term : kinds[k]) {
        out.push_back({term});
        for (std::size_t other = k + 1; other < kinds.size(); ++other) {
          for (const auto& second : kinds[other]) out.push_back({term, second});
        }
      }
    }
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

std::vector<std::string> channel_candidate_terms(const ChamberLog& log, std::size_t axis) {
  const std::size_t channels = log.temperature.size();
  if (channels < 2 || channels < log.axes()) return {};
  const std::size_t own = temperature_channel_per_axis(log).at(axis);
  std::vector<std::string> out;
  for (std::size_t other = 0; other < channels && other < kMaxTemperatureChannels; ++other) {
    if (other == own) continue;
    out.push_back(fmt::format("grad:{}-{}", own + 1, other + 1));
    out.push_back(fmt::format("gradrate:{}-{}", own + 1, other + 1));
  }
  return out;
}

SelectionRecord FeatureSelection::record(const FeatureSelectionOptions& options) const {
  SelectionRecord out;
  const bool thermal_node = options.method == FeatureSelectionOptions::Method::thermal_node;
  out.method = thermal_node ? "thermal_node" : "greedy";
  out.scored_by = scored_by;
  out.folds = held_out.blocks.size();
  out.folds_by = to_string(held_out.by);
  out.min_gain = options.min_gain;
  out.start_mse = start_mse;
  out.cv_mse = cv_mse;
  out.candidates_scored = candidates_scored;
  out.terms = terms;
  for (const auto& step : path) out.path.push_back({step.action, step.term, step.cv_mse, step.terms});
  if (temperature_channel) out.temperature_channel = *temperature_channel + 1;
  if (thermal_node) {
    out.power_on_start = options.power_on_start;
    out.node_under_dynamics = options.node_under_dynamics;
    out.cv_score = options.cv_score == FeatureSelectionOptions::CvScore::geometric ? "geometric_mean" : "pooled";
  }
  return out;
}

namespace {

// The search state of one axis. The score of a set S of k terms is its blocked CV MSE,
// penalized: J(S) = CV(S) / (1 - min_gain)^k, so a term must cut the CV MSE by more than
// min_gain to pay. Every accepted step (add, drop, a time constant moved) lowers J, so the
// search cannot cycle.
class Search {
 public:
  struct Scored {
    Terms terms;
    double cv = kInfinity;
    std::map<double, double> origin;  // time constant now -> where it was before refining
  };

  Search(ColumnCache& cache, const FeatureSelectionOptions& options, FeatureSelection& result)
      : cache_(cache), options_(options), result_(result), keep_(1.0 - options.min_gain) {
    const auto grid = time_constant_grid();
    min_tau_ = grid.front() / 4;
    max_tau_ = grid.back() * 4;
  }

  double cv(const Terms& terms) {
    options_.stop.throw_if_requested("feature search");
    ++result_.candidates_scored;
    return cache_.cv_score(terms, result_.held_out.blocks, 0).cv_mse;
  }
  double penalized(const Scored& s) const { return s.cv / std::pow(keep_, static_cast<double>(s.terms.size())); }

  // Coordinate pattern search over the distinct time constants of `start` in log scale:
  // each moves by 2^(±step) while that lowers the CV MSE, step 1/2, 1/4, 1/8, 1/16. One
  // constant shared by several terms moves as one (one physical lag). At most `budget`
  // sets are scored.
  Scored refine(Scored best, long budget) {
    long used = 0;
    for (const double step : {0.5, 0.25, 0.125, 0.0625}) {
      for (bool pass_improved = true; pass_improved && used < budget;) {
        pass_improved = false;
        for (double tau : constants(best.terms)) {
          for (bool improved = true; improved && used < budget;) {
            improved = false;
            for (const double factor : {std::pow(2.0, step), std::pow(2.0, -step)}) {
              const double moved = std::round(tau * factor);
              if (moved == tau || moved < min_tau_ || moved > max_tau_ || constants(best.terms).count(moved)) continue;
              Terms trial = with_time_constant(best.terms, tau, moved);
              ++used;
              const double value = cv(trial);
              if (value < best.cv) {
                const auto from = best.origin.find(tau);
                best.origin[moved] = from == best.origin.end() ? tau : from->second;
                if (from != best.origin.end()) best.origin.erase(tau);
                best.terms = std::move(trial);
                best.cv = value;
                tau = moved;
                improved = pass_improved = true;
                break;
              }
              if (used >= budget) break;
            }
          }
        }
      }
    }
    return best;
  }

  static std::set<double> constants(const Terms& terms) {
    std::set<double> out;
    for (const auto& name : terms) {
      for (const double tau : FeatureTerm::parse(name).time_constants()) out.insert(tau);
    }
    return out;
  }

  // "a -> b, c -> d": the constants `refine` moved, from where they were to where they are.
  static std::string moves(const Scored& s) {
    std::string out;
    for (const auto& [now, before] : s.origin) {
      if (now != before) out += fmt::format("{}{} -> {}", out.empty() ? "" : ", ", before, now);
    }
    return out;
  }

 private:
  ColumnCache& cache_;
  const FeatureSelectionOptions& options_;
  FeatureSelection& result_;
  double keep_;
  double min_tau_ = 0, max_tau_ = 0;
};

// Terms followed by those of `block` they do not hold yet, in order.
Terms with_block(const Terms& terms, const Terms& block) {
  Terms out = terms;
  for (const auto& term : block) {
    if (std::find(out.begin(), out.end(), term) == out.end()) out.push_back(term);
  }
  return out;
}

std::string joined(const Terms& terms, std::size_t from) {
  std::string out;
  for (std::size_t i = from; i < terms.size(); ++i) out += (out.empty() ? "" : ",") + terms[i];
  return out;
}

}  // namespace

FeatureSelection select_features(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline,
                                 const FeatureSelectionOptions& options) {
  ColumnCache cache(logs, axis, pipeline);
  const Eigen::VectorXd& y = cache.target();
  if (y.size() < 4 * options.folds) {
    throw UsageError(fmt::format("--features auto: {} samples are too few for {}-fold selection", y.size(),
                                 options.folds));
  }
  FeatureSelection result;
  result.held_out = cache.blocks(options.folds, options.folds_by);
  Search search(cache, options, result);
  using Scored = Search::Scored;
  Scored current{{}, search.cv({}), {}};
  result.start_mse = current.cv;

  // A candidate is one term or a block of terms sharing one lag (the coil's temperature
  // and its rate enter together).
  std::vector<Terms> candidates;
  for (const auto& term : base_candidate_terms()) candidates.push_back({term});
  for (const auto& term : channel_candidate_terms(logs.front(), axis)) candidates.push_back({term});
  for (const double tau : time_constant_grid()) {
    candidates.push_back({fmt::format("lag:{}", tau), fmt::format("lagrate:{}", tau)});
    candidates.push_back({fmt::format("lag:{}", tau), fmt::format("lagrate:{}", tau), fmt::format("lag:{}^2", tau)});
  }

  const std::size_t base_candidates = candidates.size();

  // Drops while one lowers the penalized score (a proxy taken early that later terms made
  // redundant); each unrefined, the set refined after the last.
  auto drop_while_it_pays = [&] {
    bool dropped = false;
    while (current.terms.size() > 1) {
      Scored best;
      std::string term;
      for (std::size_t i = 0; i < current.terms.size(); ++i) {
        Scored trial{current.terms, 0, {}};
        trial.terms.erase(trial.terms.begin() + static_cast<std::ptrdiff_t>(i));
        trial.cv = search.cv(trial.terms);
        if (trial.cv < best.cv) best = std::move(trial), term = current.terms[i];
      }
      if (!(search.penalized(best) < search.penalized(current))) break;
      current = std::move(best);
      result.path.push_back({"drop", term, current.cv, current.terms});
      dropped = true;
    }
    return dropped;
  };
  auto refine_and_record = [&](long budget) {
    Scored refined = search.refine({current.terms, current.cv, {}}, budget);
    if (refined.cv < current.cv) {
      result.path.push_back({"tune", Search::moves(refined), refined.cv, refined.terms});
      current = std::move(refined);
    }
  };

  // Forward steps: every candidate is scored as it stands; the best few are refined
  // (their time constants and those already chosen move together, since a new term often
  // wants the lag it shares to move), and the best refined one is taken if it pays.
  for (std::size_t step = 0; step < 4 * options.max_terms; ++step) {
    std::vector<std::pair<double, Scored>> ranked;  // penalized score, the set as it stands
    for (const auto& candidate : candidates) {
      Scored trial{with_block(current.terms, candidate), 0, {}};
      if (trial.terms.size() == current.terms.size() || trial.terms.size() > options.max_terms) continue;
      trial.cv = search.cv(trial.terms);
      ranked.emplace_back(search.penalized(trial), std::move(trial));
    }
    if (ranked.empty()) break;
    std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    Scored best;
    const std::size_t refined = std::min(ranked.size(), std::max<std::size_t>(options.refine_top, 1));
    for (std::size_t i = 0; i < refined; ++i) {
      Scored trial = search.refine(std::move(ranked[i].second), options.refine_budget);
      if (search.penalized(trial) < search.penalized(best)) best = std::move(trial);
    }
    if (!(search.penalized(best) < search.penalized(current))) break;
    const std::string moved = Search::moves(best);
    const std::size_t before = current.terms.size();
    current = {best.terms, best.cv, {}};
    result.path.push_back({"add", joined(current.terms, before) + (moved.empty() ? "" : " (" + moved + ")"),
                           current.cv, current.terms});
    if (drop_while_it_pays()) refine_and_record(options.refine_budget);
    // Terms on the lags chosen now (not on where they stood before refining).
    candidates.resize(base_candidates);
    for (auto& block : conditional_candidates(current.terms)) candidates.push_back(std::move(block));
  }
  refine_and_record(4 * options.refine_budget);
  if (drop_while_it_pays()) refine_and_record(4 * options.refine_budget);

  if (current.terms.empty()) current.terms = {"dT", "rate"};  // nothing pays: the paper's pair
  result.terms = current.terms;
  result.cv_mse = current.cv;
  return result;
}

void judge_by_svr(FeatureSelection& selection, const std::vector<ChamberLog>& logs, std::size_t axis,
                  const Pipeline& pipeline, const SvrJudgeOptions& options) {
  // The sets the search settled on: the one standing before each addition, and the last.
  std::vector<Terms> sets;
  const auto& path = selection.path;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const bool settled = i + 1 == path.size() || path[i + 1].action == "add";
    if (settled && path[i].action != "svr" &&
        std::find(sets.begin(), sets.end(), path[i].terms) == sets.end()) {
      sets.push_back(path[i].terms);
    }
  }
  if (sets.empty()) sets.push_back(selection.terms);
  if (sets.size() > options.sets) sets.erase(sets.begin(), sets.end() - static_cast<std::ptrdiff_t>(options.sets));

  std::optional<SvrTuningOptions> tuning = options.tuning;
  if (tuning) {
    tuning->evaluations = options.evaluations;
    tuning->progress = nullptr;
  }
  const double keep = 1.0 - options.min_gain;
  double best_penalized = kInfinity;
  Pipeline trial = pipeline;
  for (const auto& terms : sets) {
    trial.terms.clear();
    for (const auto& name : terms) trial.terms.push_back(FeatureTerm::parse(name));
    const FeatureTable table = feature_table(logs, trial, axis, true);
    const HeldOutBlocks held_out = cv_blocks(table.features.rows(), table.run_start,
                                             tuning ? tuning->folds : options.folds, options.folds_by);
    const Standardization scaling = Standardization::of(table.features, table.target);
    const Eigen::MatrixXd x = scaling.features(table.features);
    const Eigen::VectorXd y = scaling.target(table.target);
    double scaled_mse = 0;
    if (tuning) {
      SvrTuningOptions judged = *tuning;
      judged.blocks = held_out.blocks;
      scaled_mse = tune_svr(x, y, judged).objective_value;
    } else {
      SvrTuningOptions cv;
      cv.blocks = held_out.blocks;
      cv.solver = options.fixed;
      const SvrObjective objective(x, y, cv);
      scaled_mse = objective(options.fixed.C, sigma_of_gamma(options.fixed.gamma), options.fixed.epsilon);
    }
    const double mse = scaled_mse * scaling.target_scale * scaling.target_scale;
    selection.path.push_back({"svr", joined(terms, 0), mse, terms});
    const double penalized = mse / std::pow(keep, static_cast<double>(terms.size()));
    if (penalized < best_penalized) {
      best_penalized = penalized;
      selection.terms = terms;
      selection.cv_mse = mse;
    }
  }
  selection.scored_by = "least_squares+svr";
}

}  // namespace thermodrift
