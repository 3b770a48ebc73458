// Choosing feature terms (`--features auto`): forward selection over the thermal terms of
// features/terms.hpp, scored by blocked cross-validation in time, with the time constants
// of each candidate refined as it is tried; then, for an SVR, the last sets the search
// settled on are judged by a tuned SVR's own blocked CV. docs/features.md explains the
// candidates, the penalty and why the time constants are refined inside the search.
//
//   FeatureSelection chosen = select_features(logs, axis, pipeline, {});  // least squares
//   judge_by_svr(chosen, logs, axis, pipeline, svr_options);              // --model svr only
//   pipeline.terms = parse(chosen.terms);              // chosen.path: how it got there
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/fit_record.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/stop_token.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

struct FeatureSelectionOptions {
  // thermal_node (default): one node's static map and dynamics identified as a structure
  // (identify_thermal_node); greedy: the forward search over single terms (select_features),
  // the default before the law family showed it fits one cycle rather than the physics
  // (docs/generalization.md has both measurements).
  enum class Method { greedy, thermal_node };
  Method method = Method::thermal_node;
  std::size_t knots = 7;              // thermal_node: hinges of the node's static map
  double min_time_constant = 15;      // s: the node's lag grid starts here, steps of √2
  double max_time_constant = 5400;    // s: and stops here or at a quarter of the training span
  std::size_t max_dynamic_terms = 3;  // thermal_node: at most one Shupe term, one memory, one second lag
  // thermal_node: a set whose least-squares fit cancels more than this (cancellation():
  // the parts' spreads over the fit's, the static map one part) scores its CV MSE times
  // (cancellation / this)². A fit that is a small difference of large terms turns any
  // mismatch of one part on new data (a lag started elsewhere, another ramp rate) into a
  // large error; identified models cancel 1.5-12 times, the ones that failed 200 and more.
  double max_cancellation = 30;
  // thermal_node: with one thermometer per axis (or more), look for the node on every
  // channel, not only the axis' own: another axis' thermometer may sit on this axis' coil
  // (the rule: thermal_node.cpp; with node_under_dynamics, another channel is kept only
  // when its grown model beats the own channel's). On development laws 1-40 against the
  // own channel: 14 axes better by more than 1.5x, one worse, held-out geometric means
  // 4.69 | 6.40 -> 3.91 | 5.05; docs/features.md, "The node's thermometer".
  bool other_channels = true;
  // thermal_node: the training logs start at power-on, so the start-of-run terms (on:TAU,
  // the turn-on transient and self-heating settling through the node) are offered. False
  // for logs recorded with the unit already running: the terms would fit a transient that
  // is not there.
  bool power_on_start = true;
  // thermal_node: once the dynamic terms are grown on the node, search every node structure
  // on the grid again under them (and grow again from a better one), and when the node was
  // found on another axis' thermometer, grow on the axis' own too and keep the other only
  // if its grown model is better. The node is first chosen without them, so an unmodelled
  // memory can pick the wrong node or thermometer; docs/features.md, steps 1 and 4. False
  // only to measure what it brings.
  bool node_under_dynamics = true;
  // thermal_node: what every comparison of the search (nodes, thermometers, terms, time
  // constants, members) scores a set by, from its blocked CV. `geometric`: the geometric
  // mean of the held-out blocks' MSEs, so a set must predict the typical block better, not
  // only the pooled rows: one cycle's smoothed noise is uneven across its blocks, and a set
  // that follows the noisiest wins their pooled MSE (development law 5, x: two lags in
  // series beat a single lag by 14 % while predicting 6 of 10 blocks worse; the model grown
  // on them missed a fast programme by 19x the floor, a single lag 1.3x; docs/features.md,
  // "Scored by the typical block"). `pooled`: the pooled held-out MSE, the score before;
  // only to measure what the change brings.
  enum class CvScore { pooled, geometric };
  CvScore cv_score = CvScore::geometric;
  // Asked before each set is scored (both methods): a stop request throws Interrupted.
  StopToken stop;
  // Axes searched at once by select_features_per_axis, and searched and fitted at once by
  // calibrate; each axis' work is independent, so the result does not depend on it.
  int threads = 1;
  // Blocked CV: contiguous blocks in time. Ten, not the tuning's five: with five, each
  // block is a whole regime of a chamber cycle (the hot soak, the cold ramp), and terms
  // that happen to extrapolate into it win over the physical ones (docs/features.md).
  int folds = 10;
  // runs, with two or more training logs (separate runs): one fold per run instead.
  FoldsBy folds_by = FoldsBy::time;
  // greedy: a set of k terms is scored CV(S) / (1 - min_gain)^k: a term must cut the CV MSE by more
  // than this fraction to be taken. Smoothed gyro noise is correlated over minutes, so a
  // chamber cycle holds few independent stretches of it and small gains are mostly noise
  // followed by chance (docs/features.md has the measurements behind 10 %).
  double min_gain = 0.10;
  std::size_t max_terms = 8;
  std::size_t refine_top = 8;  // candidates of each forward step whose time constants are refined
  long refine_budget = 60;     // sets scored per refinement (four times that for the final one)
};

// The SVR's judgement of the least-squares path (judge_by_svr).
struct SvrJudgeOptions {
  // Each set's SVR is tuned as the final fit will be, with `evaluations` as its budget;
  // without tuning, it is scored at `fixed` by blocked CV over `folds`.
  std::optional<SvrTuningOptions> tuning;
  SvrOptions fixed;
  int folds = 5;
  FoldsBy folds_by = FoldsBy::time;  // as FeatureSelectionOptions::folds_by
  long evaluations = 20;     // AFSA budget per judged set
  std::size_t sets = 3;      // the last sets the search settled on
  double min_gain = 0.10;    // the same penalty per term as the search
};

struct SelectionStep {
  // "add", "drop", "tune" (time constants moved), "svr" (a set judged by the SVR); thermal_node
  // also "node", "member" (one search's final set) and "average" (the members averaged)
  std::string action;
  std::string term;    // the term(s) added or dropped, "TAU -> TAU'" moves, or the set judged
  double cv_mse = 0;   // (°/h)², the score after the step (least squares, by options.cv_score for
                       // thermal_node; the SVR's for "svr"; "average": the pooled CV MSE)
  std::vector<std::string> terms;  // the set after the step
};

struct FeatureSelection {
  std::vector<std::string> terms;
  std::string scored_by = "least_squares";  // "least_squares" or "least_squares+svr"
  double start_mse = 0;  // the score of the constant model (°/h)², as the path's
  double cv_mse = 0;     // CV MSE of the chosen set (pooled over the held-out blocks)
  std::vector<SelectionStep> path;
  std::size_t candidates_scored = 0;
  HeldOutBlocks held_out;  // the least-squares CV's blocks (their count and kind go to the JSON)
  // thermal_node: when several searches were averaged, their least-squares fits averaged
  // over `terms` (the union of their sets): the linear model, or the SVR's linear part,
  // instead of a least-squares refit on the union.
  std::optional<LinearModel> linear_fit;
  // The term sets whose fits linear_fit averages (each a subset of `terms`).
  std::vector<std::vector<std::string>> averaged_sets;
  // thermal_node: the temperature channel the node was found on, when not the axis' own
  // (Pipeline::temperature_channel).
  std::optional<std::size_t> temperature_channel;

  SelectionRecord record(const FeatureSelectionOptions& options) const;
};

// The candidate terms the greedy search starts from (before conditional ones such as
// gradrate:TAU:TG, offered once lag:TAU or lagrate:TAU is chosen).
std::vector<std::string> base_candidate_terms();
// With several temperature channels (one per axis, or more): the difference of the
// axis' own channel and each other one, and its rate (grad:A-B, gradrate:A-B).
std::vector<std::string> channel_candidate_terms(const ChamberLog& log, std::size_t axis);
// The lag time-constant grid, s: 60·√2^k up to about an hour.
std::vector<double> time_constant_grid();

// Chooses terms for one axis of the (time-ordered) training logs with `pipeline`'s
// smoothing, rate span, decimation and reference, by least squares. Throws UsageError
// when there are too few samples for the folds.
FeatureSelection select_features(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline,
                                 const FeatureSelectionOptions& options);

// One thermal node per axis (docs/features.md): the node's lag chosen by blocked CV on a
// grid limited to what the log can identify (two lags in series or a lag with a lead when
// they pay), a piecewise-linear map of its temperature, its rate and the sensor's, then
// dynamic terms linear in the node's state (Shupe gradient rate, direction memory, play,
// a second lag) while each pays; every constant refined by a pattern search and a simplex.
FeatureSelection identify_thermal_node(const std::vector<ChamberLog>& logs, std::size_t axis,
                                       const Pipeline& pipeline, const FeatureSelectionOptions& options);

// Of the sets `selection`'s search settled on after each addition (the last `sets` of
// them), keeps the one whose AFSA-tuned SVR has the lowest penalized blocked CV MSE; adds
// an "svr" step per set judged. A least-squares search proposes (it scores thousands of
// sets in a second); the model that will be fitted decides.
void judge_by_svr(FeatureSelection& selection, const std::vector<ChamberLog>& logs, std::size_t axis,
                  const Pipeline& pipeline, const SvrJudgeOptions& options);

}  // namespace thermodrift
