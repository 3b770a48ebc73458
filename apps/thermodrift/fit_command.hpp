// `thermodrift fit` in two parts the command line and the Python package share: the
// options (declared once, so a keyword of td.fit is checked and worded as the option is)
// and the fit itself, from the --data files or from logs already in memory.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "data_options.hpp"
#include "thermodrift/stop_token.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift::cli {

struct FitArguments {
  DataOptions data;
  std::string model = "linear";
  double C = 0;
  double sigma = 0;
  double gamma = 0;
  double epsilon = 0.01;
  double tolerance = 1e-3;
  double rate_span = 0;
  std::size_t decimate = 0;
  std::vector<std::string> features{"dT", "rate"};
  FeatureSelectionOptions::Method identify = FeatureSelectionOptions{}.method;
  std::string node_channel = "any";
  std::string log_start = "power-on";
  std::string tune;
  std::string objective = "cv";
  std::uint64_t seed = 1;
  int threads = 0;
  long evaluations = 49;
  int folds = 5;
  std::string folds_by = "time";
  bool tune_epsilon = false;
  bool keep_kernel = false;
  std::size_t max_vectors = 0;
  std::string kernel = "auto";
  std::size_t landmarks = SvrOptions{}.landmarks;
  std::string out;
  bool json = false;
};

// Declares every option of fit on `app` but --out and --json (the command's own), with
// --data required when `data_required`.
void add_fit_options(CLI::App& app, FitArguments& args, bool data_required = true);

// Progress of a fit: tuning and the feature search's steps, per axis of `axes`.
struct FitProgress {
  std::function<bool(std::size_t axis, std::size_t axes, const optim::Progress&)> tuning;
  std::function<void(std::size_t axis, std::size_t axes, const std::string& what)> step;
};

struct FitRun {
  Calibration calibration;
  std::vector<ChamberLog> logs;  // what was fitted (empty for --format libsvm)
};

// Checks the options' combinations (UsageError) and fits: the --data files when `logs` is
// empty, else `logs`, read as `spec` says (the spec stored in the model). `app` is the one
// `args` was parsed by (which options were given).
FitRun fit_from_arguments(const FitArguments& args, const CLI::App& app, std::vector<ChamberLog> logs,
                          const LogSpec& spec, const StopToken& stop, const FitProgress& progress);

// What a user must hear about a fit, one line each: per axis fit_warnings (an SVR that did
// not converge, a model worse than none in-sample) and where the training data did not
// cover what the model will be asked (TrainingEnvelope::coverage_warnings).
std::vector<std::string> fit_run_warnings(const Calibration& calibration);

}  // namespace thermodrift::cli
