// Choosing feature terms (`--features auto`): greedy forward selection over the thermal
// terms of features/terms.hpp, scored by blocked cross-validation in time, then a search
// of each chosen time constant. docs/features.md explains the candidates and the penalty.
//
//   FeatureSelectionOptions options;                  // scored by least squares
//   FeatureSelection chosen = select_features(logs, axis, pipeline, options);
//   pipeline.terms = parse(chosen.terms);              // chosen.path: how it got there
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/svr.hpp"

namespace thermodrift {

struct FeatureSelectionOptions {
  // "linear" or "stepwise": each candidate set is scored by a least-squares fit (terms as
  // given). "svr": the best `shortlist` candidates by least squares are scored by an SVR
  // at the fixed `svr` options (standardized units), and the SVR score decides.
  std::string model = "linear";
  int folds = 5;               // blocked CV: contiguous blocks in time
  double min_gain = 0.03;      // a term is taken only if it cuts the CV MSE by more than this fraction
  std::size_t max_terms = 8;
  std::size_t shortlist = 3;   // svr only
  SvrOptions svr;              // svr only
};

struct SelectionStep {
  std::string action;  // "add", "tune" (a time constant moved) or "drop"
  std::string term;    // the term(s) added or dropped, or "TAU -> TAU'" for a time constant
  double cv_mse = 0;   // (°/h)², after the step
  std::vector<std::string> terms;  // the set after the step
};

struct FeatureSelection {
  std::vector<std::string> terms;
  double start_mse = 0;  // CV MSE of the constant model (°/h)²
  double cv_mse = 0;     // CV MSE of the chosen set, as scored
  std::vector<SelectionStep> path;
  std::size_t candidates_scored = 0;

  nlohmann::json to_json(const FeatureSelectionOptions& options) const;
};

// The candidate terms the greedy search starts from (before conditional ones such as
// gradrate:TAU:TG, offered once lag:TAU or lagrate:TAU is chosen).
std::vector<std::string> base_candidate_terms();
// The lag time-constant grid, s: 60·√2^k up to about an hour.
std::vector<double> time_constant_grid();

// Chooses terms for one axis of the (time-ordered) training logs with `pipeline`'s
// smoothing, rate span, decimation and reference. Throws UsageError when there are too
// few samples for the folds.
FeatureSelection select_features(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline,
                                 const FeatureSelectionOptions& options);

}  // namespace thermodrift
