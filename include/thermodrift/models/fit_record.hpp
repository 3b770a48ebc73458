// How an axis' model was fitted, typed: what was tuned, how, with what result. calibrate
// fills it, fit, report, compress and the Python module read its fields, and it turns into
// JSON in one place, the model file's "fit" object (fit_record_to_json /
// fit_record_from_json). Informational: nothing a prediction needs is here.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "thermodrift/models/metrics.hpp"

namespace thermodrift {

// The SVR's hyperparameters as fitted (σ and γ = 1/(2σ²) both, for whoever reads the file).
struct SvrParameters {
  double C = 0;
  double sigma = 0;
  double gamma = 0;
  double epsilon = 0;
};

// One point of a tuning run's convergence: the best objective after so many evaluations.
struct TuningPoint {
  long evaluations = 0;
  double best_value = 0;  // (°/h)²
};

// How C and σ (and ε) were tuned (tune/svr_tuning.hpp names the methods and objectives).
struct TuningRecord {
  std::string method;             // afsa, grid, random
  std::string objective;          // cv, holdout, train
  bool optimistic = false;        // the objective scored the data it was fitted on
  std::size_t folds = 0;          // blocks of the CV
  std::string folds_by = "time";  // time (contiguous blocks) or runs (one per training log)
  double objective_mse = 0;       // the tuned point's objective, (°/h)²
  long fits = 0;                  // SVR fits the tuning made
  long capped_fits = 0;           // of which stopped at the iteration cap
  std::uint64_t seed = 0;
  std::array<double, 2> C_box{};      // the search box
  std::array<double, 2> sigma_box{};
  // ε's box when it was tuned; else the fixed ε.
  std::optional<std::array<double, 2>> epsilon_box;
  double epsilon = 0;
  std::vector<TuningPoint> history;
};

// The final SVR fit's solver (models/svr.hpp's SvrSummary, named).
struct SolverRecord {
  std::string termination;  // converged, iteration_cap, ...
  long iterations = 0;
  std::size_t support_vectors = 0;
  double dual_objective = 0;
  std::string kernel;  // exact, nystrom, low_rank
  // A factored kernel: its rank, the kernel it leaves unexplained, the samples outside the tube.
  std::optional<std::size_t> landmarks;
  std::optional<double> mean_kernel_residual;
  std::optional<std::size_t> samples_outside_tube;
};

// A partially linear SVR's kernel judged after tuning, by nested CV over the feature
// search's blocks: each fold refits the linear part without its block and trains the
// kernel (the tuned C, σ, ε) on that fit's residual. The kernel is kept when it cuts the
// linear part's CV MSE by the search's margin; else the model is its linear part alone.
struct KernelCheckRecord {
  std::size_t folds = 0;
  std::string folds_by = "time";
  double with_kernel_mse = 0;  // (°/h)², the held-out blocks pooled
  double linear_part_mse = 0;
  double min_gain = 0;
  bool kept = true;
};

// An SVR reduced to fewer support vectors (models/svr_model.hpp's compress).
struct CompressionRecord {
  std::string method;
  std::size_t from_vectors = 0;
  std::size_t to_vectors = 0;
  std::size_t points = 0;    // where the reduced function was matched to the full one
  double rms_change = 0;     // of the prediction there, °/h
  double max_change = 0;
  std::string unit = "deg/h";
  // At fit time (fit --max-vectors): the in-sample MSE before and after, (°/h)².
  std::optional<double> training_mse_before;
  std::optional<double> training_mse_after;
  // By `thermodrift compress`: the MSE on its --data logs before and after, from `settle` s on.
  std::optional<double> data_mse_before;
  std::optional<double> data_mse_after;
  std::optional<std::vector<std::string>> data;
  std::optional<double> settle_seconds;
};

// One step of a feature search (tune/feature_selection.hpp's SelectionStep).
struct SelectionStepRecord {
  std::string action;
  std::string term;
  double cv_mse = 0;
  std::vector<std::string> terms;
};

// How --features auto chose the terms.
struct SelectionRecord {
  std::string method;      // thermal_node or greedy
  std::string scored_by;   // what scored the final set
  std::size_t folds = 0;
  std::string folds_by = "time";
  double min_gain = 0;
  double start_mse = 0;    // the CV MSE of the starting set, (°/h)²
  double cv_mse = 0;       // of the chosen set
  std::size_t candidates_scored = 0;
  std::vector<std::string> terms;
  std::vector<SelectionStepRecord> path;
  std::optional<std::size_t> temperature_channel;  // 1-based, when the node is on another channel
  std::optional<bool> power_on_start;              // thermal_node only
  std::optional<bool> node_under_dynamics;
  // thermal_node: what the path's scores are: "geometric_mean" of the held-out blocks'
  // MSEs, or "pooled" MSE (absent in files written before it was recorded: pooled).
  std::optional<std::string> cv_score;
};

// One step of a stepwise regression (models/linear.hpp's fit_stepwise).
struct StepwiseStepRecord {
  std::string action;
  std::string regressor;
  double F = 0;
};

struct FitRecord {
  std::vector<std::string> terms;
  bool averaged_linear_part = false;  // the linear part is the feature search's averaged fit
  bool partially_linear = false;      // SVR on the residual of a linear part
  std::vector<StepwiseStepRecord> stepwise_path;
  std::optional<SvrParameters> params;
  std::optional<bool> standardized;
  std::optional<TuningRecord> tuning;
  std::optional<SolverRecord> solver;
  std::optional<long> evaluations;  // SVR fits behind the final one (1 when not tuned)
  std::optional<CompressionRecord> compressed;
  std::optional<KernelCheckRecord> kernel_check;
  std::optional<SelectionRecord> feature_selection;
  std::optional<std::size_t> training_samples;
  std::optional<ResidualMetrics> in_sample;
};

nlohmann::json fit_record_to_json(const FitRecord& record);
nlohmann::json to_json(const CompressionRecord& record);
nlohmann::json to_json(const KernelCheckRecord& record);
nlohmann::json to_json(const SelectionRecord& record);
nlohmann::json to_json(const TuningRecord& record);
nlohmann::json to_json(const SolverRecord& record);
nlohmann::json to_json(const SvrParameters& params);

// The record a model file's "fit" object holds. Keys it does not know (written by earlier
// versions) are ignored; a known key of the wrong type is an Error naming it.
FitRecord fit_record_from_json(const nlohmann::json& json);

}  // namespace thermodrift
