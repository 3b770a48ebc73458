// Calibration: from chamber logs to a drift model, one model per gyro axis (the paper's
// self-regression). Joins the feature pipeline, the models and, for SVR, the tuner.
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/io/libsvm_reader.hpp"
#include "thermodrift/models/metrics.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/stop_token.hpp"
#include "thermodrift/tune/feature_selection.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

struct CalibrationOptions {
  ModelKind model = ModelKind::linear;
  double smooth_seconds = 100;             // moving-average window (the paper: 100 s)
  std::optional<double> rate_span_seconds; // dT/dt span; default: the smoothing window (at least 1 s)
  std::optional<std::size_t> decimation;   // default: about 10 samples per smoothing window
  std::vector<std::string> terms{"dT", "rate"};  // feature terms (the paper's pair); {"auto"}: chosen per axis
  SvrOptions svr;                          // C, gamma, epsilon, tolerance for --model svr (standardized units)
  std::optional<SvrTuningOptions> tuning;  // tune C, σ (and ε) per axis instead of using `svr`'s
  // --model svr: at most this many support vectors per axis, by the reduced set fitted at
  // the training samples (models/svr_reduce.hpp); the record is fit.compressed.
  std::optional<std::size_t> max_vectors;
  // Cancellation of the whole calibration: calibrate and fit_model hand it to the feature
  // search, the SVR's judgement of feature sets, the tuning and every SVR fit (replacing
  // the token of `svr`, `tuning->solver` and `selection`), so a stop request throws
  // Interrupted within a fraction of a second wherever the work is.
  StopToken stop;
  // Progress of the tuning of axis `axis` (0-based); returning false stops the run.
  std::function<bool(std::size_t axis, const optim::Progress&)> tuning_progress;
  // With terms {"auto"}: the least-squares selections per axis when already made (a study
  // fitting several models shares one search); empty: calibrate searches.
  std::vector<FeatureSelection> selections;
  FeatureSelectionOptions selection;       // how terms {"auto"} are identified
  // Cross-validation of the feature search and of the SVR tuning: time (default), blocked
  // folds in time over the logs in order; runs, with two or more logs (separate runs), one
  // fold per run (leave-one-run-out). Overrides selection.folds_by. Two runs held out in
  // turn scored worse choices than ten blocks on the development laws (docs/tuning.md).
  FoldsBy folds_by = FoldsBy::time;
  // Set by calibrate for terms the thermal node identified, which are built for a linear
  // fit: svr fits least squares on the terms and the SVR on its residual
  // (SvrModel::linear_part); stepwise chooses among the terms themselves, without the
  // squares and products it adds to other terms (products of hinges extrapolate as
  // parabolas: z of the demo went from 1.6x to 27x the floor held out with them).
  bool partially_linear = false;
  // A partially linear SVR's kernel is judged after tuning by nested CV and left out when
  // it does not cut the linear part's CV MSE by selection.min_gain (fit_model); true keeps
  // it without the check, as the paper's SVR would.
  bool keep_kernel = false;
  // A line of progress of axis `axis` outside tuning (feature selection); may be empty.
  std::function<void(std::size_t axis, const std::string&)> selection_progress;
};

// What a fit is asked, each option given or not, and the one policy that turns it into
// CalibrationOptions, so that `thermodrift fit` and any other front end (the Python
// package) share every default. For the SVR, as the paper: C and σ (or γ) are tuned per
// axis (AFSA unless `tune` names another method) unless both are given and `tune` is not;
// the solver's own values are the given ones, else C = 100 and σ = 1. Options of the SVR
// given with another model are the front end's to refuse, in its user's words.
struct FitRequest {
  ModelKind model = ModelKind::linear;
  double smooth_seconds = 100;
  std::optional<double> rate_span_seconds;
  std::optional<std::size_t> decimation;
  std::vector<std::string> terms{"dT", "rate"};
  FeatureSelectionOptions::Method identify = FeatureSelectionOptions{}.method;
  bool other_channels = FeatureSelectionOptions{}.other_channels;  // the node on any thermometer
  bool power_on_start = FeatureSelectionOptions{}.power_on_start;  // the logs start at power-on
  FoldsBy folds_by = FoldsBy::time;
  int threads = 0;  // 0: every core
  std::uint64_t seed = 1;
  // SVR
  std::optional<double> C;
  std::optional<double> sigma;
  std::optional<double> gamma;  // instead of sigma
  double epsilon = 0.01;
  double tolerance = 1e-3;
  std::optional<std::string> tune;  // afsa, grid or random
  std::string objective = "cv";
  long evaluations = 49;
  int folds = 5;
  bool tune_epsilon = false;
  bool keep_kernel = false;  // CalibrationOptions::keep_kernel
  std::optional<std::size_t> max_vectors;
  SvrApproximation approximation = SvrApproximation::automatic;  // the kernel: exact, Nyström, or by size
  std::size_t landmarks = SvrOptions{}.landmarks;
  StopToken stop;
};
// Throws UsageError for sigma and gamma both given, an unknown tune method or objective,
// or tuning options that are not valid.
CalibrationOptions calibration_options(const FitRequest& request);

// True when options.terms is {"auto"}: calibrate chooses terms per axis (tune/feature_selection.hpp).
bool chooses_features(const CalibrationOptions& options);

// What a user must hear about a fitted axis, one line each (empty when nothing): an SVR
// that stopped at its iteration cap before converging (usable, not optimal), and a model
// that leaves more drift than it found on its own training data.
std::vector<std::string> fit_warnings(const AxisModel& axis, const ResidualMetrics& in_sample);

// A model whose expected held-out MSE (or, for a fit without CV, its in-sample MSE) is more
// than this many times the noise-floor estimate does not describe the unit's drift down to
// the noise, and such models often miss other programmes by far: of the development laws'
// axes above it, 30 of 40 missed another programme by more than 10 times the floor, of
// those below it 28 of 80 (docs/generalization.md, "Far from the floor").
inline constexpr double kFarFromFloor = 2.0;

// One axis' figure over the noise-floor estimate, for far_from_floor_warning.
struct FloorRatio {
  std::string axis;
  double ratio = 0;
};

// The warning, one line, for the axes of one model whose ratio is above kFarFromFloor
// (nothing when none is): `held_out` says the ratio is the expected held-out MSE's (else the
// in-sample MSE's), `searched` that the terms were chosen (--features auto; else the line
// names it as a remedy), `training_logs` how many logs the model was fitted on (with more
// than one, the advice is a further programme at other rates and ranges), `data_option`
// how the caller's user gives fit another log ("--data"; the report, which reads one log,
// says "fit --data").
std::optional<std::string> far_from_floor_warning(const std::vector<FloorRatio>& axes, bool held_out, bool searched,
                                                  std::size_t training_logs,
                                                  const std::string& data_option = "--data");

// What an axis' fit expects held out: the CV MSE (°/h)² its choices were scored by
// (the tuned SVR's CV, else the feature search's least-squares CV) and where it comes from.
// A selection score on the training data, so an estimate, not a held-out measurement.
struct ExpectedHeldOut {
  double cv_mse = 0;
  std::string from;
};
std::optional<ExpectedHeldOut> expected_held_out(const FitRecord& fit);

// The least-squares selection of every axis of `logs` (terms {"auto"}), with the
// pipeline calibrate would build; the study shares it among the models it fits.
std::vector<FeatureSelection> select_features_per_axis(const std::vector<ChamberLog>& logs,
                                                       const CalibrationOptions& options);

// Which temperature channel feeds each axis: one channel for all axes, or one per axis
// (channel a for axis a; channels after those serve grad terms). Throws UsageError otherwise.
std::vector<std::size_t> temperature_channel_per_axis(const ChamberLog& log);

// The temperature columns after the axes' own that the grad terms of `pipelines` read,
// up to the highest (DriftModel::extra_temperature_columns). UsageError when a term reads
// a channel the log does not have, or the log has no column per axis to count from.
std::vector<std::string> extra_temperature_columns(const std::vector<ChamberLog>& logs, const LogSpec& spec,
                                                   const std::vector<Pipeline>& pipelines);

struct AxisCalibration {
  ResidualMetrics in_sample;   // on every ready (undecimated) sample of the training logs
  std::size_t training_samples = 0;  // after decimation
  double seconds = 0;
  double tuning_seconds = 0;  // of `seconds`, spent tuning (SVR only)
};

struct Calibration {
  DriftModel model;
  std::vector<AxisCalibration> axes;
};

// Fits one model per axis over all `logs` together (each log is its own segment: no
// smoothing across files). `spec` is how the logs were read; it is stored in the model.
Calibration calibrate(const std::vector<ChamberLog>& logs, const LogSpec& spec,
                      const CalibrationOptions& options);

// One model of kind options.model fitted to (features, target); `fit` describes how.
// SVR features and target are standardized inside the model when `standardize`.
// `fit` goes into the model file, so it holds no timings: the same inputs and seed give
// the same bytes on every run and with any thread count.
struct FittedModel {
  std::variant<LinearModel, SvrModel> model;
  FitRecord fit;
  double tuning_seconds = 0;
};
// What an identification hands the model on top: its linear fit (FeatureSelection::
// linear_fit; absent: least squares on the terms), the term sets that fit averages, and
// the held-out blocks of its CV over the rows of the features.
struct IdentifiedLinearPart {
  std::optional<LinearModel> fit;
  std::vector<std::vector<std::string>> averaged_sets;
  HeldOutBlocks held_out;
};
// `axis` labels tuning progress. `identified->fit`, when given, is the linear model, or the
// partially linear SVR's linear part, instead of a least-squares fit; stepwise ignores it.
// A partially linear SVR tuned by CV with `identified` has its kernel judged after tuning
// by nested CV over identified->held_out (KernelCheckRecord): kept when it cuts the linear
// part's CV MSE by options.selection.min_gain, else left out (the SVR has no support
// vectors: its linear part alone).
FittedModel fit_model(const Eigen::MatrixXd& features, const Eigen::VectorXd& target,
                      const std::vector<std::string>& terms, const CalibrationOptions& options,
                      bool standardize, std::size_t axis = 0, const IdentifiedLinearPart* identified = nullptr);
std::size_t minimum_samples(ModelKind model, std::size_t terms);

// libsvm-format data is used exactly as given: no smoothing, no pipeline, no scaling, so
// the result compares number for number with libsvm's svm-train (one axis, "label").
Calibration calibrate_libsvm(const LabelledData& data, const std::string& source,
                             const CalibrationOptions& options);
ResidualMetrics evaluate_libsvm(const DriftModel& model, const LabelledData& data, const std::string& source);

// The pipeline's ready samples of one axis of several logs, in order.
FeatureTable feature_table(const std::vector<ChamberLog>& logs, const Pipeline& pipeline,
                           std::size_t axis, bool decimate);

// Metrics of a fitted model on logs it may not have seen (every ready sample).
// Samples less than `settle_seconds` after the start of a log (or a gap) are left out:
// the lags start there in equilibrium, which a log begun mid-transient is not.
std::vector<ResidualMetrics> evaluate(const DriftModel& model, const std::vector<ChamberLog>& logs,
                                      double settle_seconds = 0);
// The same metrics with the count of the samples outside the model's training envelope.
struct AxisEvaluation {
  ResidualMetrics metrics;
  std::optional<EnvelopeTally> outside_envelope;  // when the model file has an envelope
  // LogStart::estimated: per log, the weight of the running start (0: power-on, 1: running)
  // its settling rows chose.
  std::vector<double> running_weight;
  // The judged rows (each log's own row numbers, log after log) and their prediction, as
  // the metrics saw them.
  std::vector<std::size_t> rows;
  std::vector<double> predicted;
};
// Where a log starts (evaluate --log-start). `power_on`: the lags start in equilibrium at its
// first row, as a unit switched on there is. `running`: the log is cut from a longer
// recording, so each log is streamed after the history with_ramp_history gives it, and its
// settling counts from its own first row. `estimated`: the prediction is power-on's plus a
// weight w in [0, 1] times (running's - power-on's), w the least-squares fit of that
// difference to power-on's residual on the log's settling rows (ready, before
// `settle_seconds`), which are not judged; without settling rows w is 0 (power-on).
enum class LogStart { power_on, running, estimated };
// Their names, as evaluate --log-start takes them (UsageError for any other).
LogStart parse_log_start(const std::string& name);
std::string log_start_name(LogStart start);
// `stop` is asked per axis and log and every 4096 predicted samples (Interrupted).
std::vector<AxisEvaluation> evaluate_axes(const DriftModel& model, const std::vector<ChamberLog>& logs,
                                          double settle_seconds = 0, const StopToken& stop = {},
                                          LogStart start = LogStart::power_on);
// Metrics on the rows of `log` from `first_row` on, the features streamed from its first
// row: the held-out part of one continuous log, with filters and lags carried into it
// as a running compensator carries them (they see temperatures only, never the gyro).
std::vector<ResidualMetrics> evaluate_from(const DriftModel& model, const ChamberLog& log, std::size_t first_row);

}  // namespace thermodrift
