// thermodrift fit: one drift model per gyro axis, written to one model file.
#include <fmt/format.h>

#include <algorithm>
#include <memory>

#include "commands.hpp"
#include "fit_command.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "output.hpp"
#include "progress.hpp"
#include "lists.hpp"
#include "numbers.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift::cli {

namespace {

// The SVR's C and σ are tuned together or both given (calibration_options refuses a value
// tuning would replace); a tuning option given without tuning is a usage error too, which
// only the command line can tell from its default. Returns whether C and σ are tuned.
bool check_svr_parameters(const CLI::App& app) {
  const bool fixed = app.count("--C") > 0 && app.count("--sigma") + app.count("--gamma") > 0 && !app.count("--tune");
  if (fixed) {
    for (const char* option : {"--objective", "--evaluations", "--folds", "--tune-epsilon"}) {
      if (app.count(option)) {
        throw UsageError(fmt::format("{} applies when C and σ are tuned, not with --C and --sigma given", option));
      }
    }
  }
  if (app.count("--epsilon") && app.count("--tune-epsilon")) {
    throw UsageError("--epsilon with --tune-epsilon: tuning chooses ε; give one of them");
  }
  return !fixed;
}

}  // namespace

FitRun fit_from_arguments(const FitArguments& args, const CLI::App& app, std::vector<ChamberLog> logs,
                          const LogSpec& spec, const StopToken& stop, const FitProgress& progress) {
  bool tuned = false;
  const ModelKind kind = *model_kind_named(args.model);  // --model accepts the kinds' names only
  if (kind != ModelKind::svr) {
    // Never silently ignored: the SVR's and its tuning's options with another model.
    for (const char* option : {"--C", "--sigma", "--gamma", "--epsilon", "--tol", "--tune", "--objective",
                               "--evaluations", "--folds", "--tune-epsilon", "--max-vectors", "--kernel",
                               "--landmarks", "--keep-kernel"}) {
      if (app.count(option)) throw UsageError(fmt::format("{} applies to --model svr, not {}", option, args.model));
    }
  } else {
    tuned = check_svr_parameters(app);
  }
  const bool auto_features = args.features.size() == 1 && args.features.front() == "auto";
  check_identify(app, args.features);
  if (app.count("--folds-by") && !auto_features && !tuned) {
    throw UsageError("--folds-by applies to the cross-validation of --features auto and of the SVR's tuning");
  }
  const bool identifies = auto_features && args.identify == FeatureSelectionOptions::Method::thermal_node;
  if (app.count("--keep-kernel") && !(tuned && identifies)) {
    throw UsageError("--keep-kernel applies to a tuned SVR on --features auto with the thermal-node identification");
  }
  for (const char* option : {"--node-channel", "--log-start"}) {
    if (app.count(option) && !(auto_features && args.identify == FeatureSelectionOptions::Method::thermal_node)) {
      throw UsageError(fmt::format("{} applies to --features auto with the thermal-node identification", option));
    }
  }
  FitRequest request;  // the library holds the defaults and the rule of when to tune
  request.model = kind;
  request.smooth_seconds = args.data.smooth;
  if (args.rate_span > 0) request.rate_span_seconds = args.rate_span;
  if (args.decimate > 0) request.decimation = args.decimate;
  request.terms = args.features;
  request.identify = args.identify;
  request.other_channels = args.node_channel == "any";
  request.power_on_start = args.log_start == "power-on";
  request.folds_by = parse_folds_by(args.folds_by);
  request.threads = args.threads;
  request.seed = args.seed;
  if (app.count("--C")) request.C = args.C;
  if (app.count("--sigma")) request.sigma = args.sigma;
  if (app.count("--gamma")) request.gamma = args.gamma;
  request.epsilon = args.epsilon;
  request.tolerance = args.tolerance;
  if (!args.tune.empty()) request.tune = args.tune;
  request.objective = args.objective;
  request.evaluations = args.evaluations;
  request.folds = args.folds;
  request.tune_epsilon = args.tune_epsilon;
  request.keep_kernel = args.keep_kernel;
  if (app.count("--max-vectors")) request.max_vectors = args.max_vectors;
  request.approximation = svr_approximation_from_string(args.kernel);
  request.landmarks = args.landmarks;
  request.stop = stop;
  CalibrationOptions options = calibration_options(request);
  std::size_t axis_count = 1;
  if (progress.tuning) {
    options.tuning_progress = [&](std::size_t axis, const optim::Progress& p) { return progress.tuning(axis, axis_count, p); };
  }
  if (progress.step) {
    options.selection_progress = [&](std::size_t axis, const std::string& what) { progress.step(axis, axis_count, what); };
  }
  FitRun run;
  if (args.data.format == "libsvm") {
    if (!logs.empty() || args.data.files.size() != 1) throw UsageError("--format libsvm takes one --data file");
    run.calibration =
        calibrate_libsvm(read_libsvm(args.data.files.front(), stop), args.data.files.front(), options);
    return run;
  }
  if (logs.empty()) {
    logs = args.data.read(spec, args.data.warm_up_seconds(args.rate_span), stop);
  } else if (!args.data.files.empty()) {
    throw UsageError("give the data once: --data files or logs in memory, not both");
  }
  axis_count = logs.front().axes();
  run.calibration = calibrate(logs, spec, options);
  run.logs = std::move(logs);
  return run;
}

std::vector<std::string> fit_run_warnings(const Calibration& calibration) {
  std::vector<std::string> warnings;
  for (std::size_t a = 0; a < calibration.model.axes.size(); ++a) {
    const auto& axis = calibration.model.axes[a];
    for (const auto& warning : fit_warnings(axis, calibration.axes[a].in_sample)) warnings.push_back(warning);
    if (!axis.envelope) continue;
    for (const auto& warning : axis.envelope->coverage_warnings()) {
      warnings.push_back(fmt::format("{}: {}", axis.name, warning));
    }
  }
  return warnings;
}

namespace {

int run_fit(const FitArguments& args, const CLI::App& app) {
  ProgressPrinter printer("thermodrift fit");
  FitProgress progress;
  progress.tuning = [&](std::size_t axis, std::size_t axes, const optim::Progress& p) { return printer.tuning(axis, axes, p); };
  progress.step = [&](std::size_t axis, std::size_t axes, const std::string& what) { printer.step(axis, axes, what); };
  const LogSpec spec = args.data.format == "libsvm" ? LogSpec{} : args.data.spec();
  // Opened first: a reader of a FIFO gets an end of file, not a wait for ever, when the
  // log is refused or the fit stops (a file output is not replaced then).
  AtomicFile out(args.out, args.data.files);
  FitRun run = fit_from_arguments(args, app, {}, spec, interrupt_token(), progress);
  const Calibration& calibration = run.calibration;
  const std::vector<ChamberLog>& logs = run.logs;
  save_drift_model(calibration.model, out);
  // Printed on stderr as they come, and listed in --json for a script that reads only stdout.
  nlohmann::json warnings = nlohmann::json::array();
  auto warn_and_keep = [&](const std::string& warning) {
    warn(warning);
    warnings.push_back(warning);
  };
  for (const auto& warning : fit_run_warnings(calibration)) warn_and_keep(warning);

  nlohmann::json result = {{"command", "fit"}, {"model_file", args.out}, {"evaluation", "in-sample"}};
  nlohmann::json axes = nlohmann::json::array();
  for (std::size_t a = 0; a < calibration.model.axes.size(); ++a) {
    const auto& axis = calibration.model.axes[a];
    nlohmann::json entry = calibration.axes[a].in_sample.to_json();
    entry["name"] = axis.name;
    entry["model"] = axis.kind;
    entry["params"] = axis.fit.params ? to_json(*axis.fit.params) : nlohmann::json::object();
    entry["evaluations"] = axis.fit.evaluations.value_or(1);
    entry["seconds"] = calibration.axes[a].seconds;
    entry["training_samples"] = calibration.axes[a].training_samples;
    entry["terms"] = axis.pipeline.term_names();
    if (const auto& selection = axis.fit.feature_selection) {
      entry["feature_selection"] = {{"scored_by", selection->scored_by}, {"cv_mse", selection->cv_mse},
                                    {"steps", selection->path.size()}};
    }
    if (const auto& tuning = axis.fit.tuning) {
      entry["tuning"] = {{"method", tuning->method}, {"objective", tuning->objective},
                         {"objective_mse", tuning->objective_mse}, {"optimistic", tuning->optimistic},
                         {"seconds", calibration.axes[a].tuning_seconds}};
    }
    if (axis.envelope) {
      entry["training_envelope"] = axis.envelope->to_json();
    }
    if (!logs.empty() && axis.pipeline.smooth_seconds > 0) {
      add_noise_floor(entry, estimate_noise_floor(logs, a, axis.pipeline.smooth_seconds));
    }
    add_expected_held_out(entry, axis.fit);
    if (const auto warning = far_from_floor_warning(entry, logs.size())) warn_and_keep(*warning);
    if (const auto& compressed = axis.fit.compressed) {
      entry["compressed"] = to_json(*compressed);
      if (!args.json) {
        print_compression(axis.name, *compressed, compressed->training_mse_before, compressed->training_mse_after,
                          "on the fitted samples, in-sample");
      }
    }
    axes.push_back(entry);
  }
  result["axes"] = axes;
  result["warnings"] = warnings;
  if (!logs.empty()) {  // how many samples each step used (the first axis; the others alike)
    std::size_t rows = 0, samples = 0, bursts = 0;
    for (const auto& log : logs) {
      rows += log.bursts ? log.bursts->rows : log.rows();
      samples += log.rows();
      if (log.bursts) bursts += log.bursts->bursts;
    }
    const auto& first = calibration.model.axes.front();
    result["samples"] = {{"rows", rows},
                         {"burst_means", bursts},
                         {"ready", calibration.axes.front().in_sample.samples},
                         {"fitted", calibration.axes.front().training_samples},
                         {"decimation", first.pipeline.decimation}};
    if (!args.json) {
      fmt::print("samples: {} rows in {} log(s){} -> {} ready after the warm-up ({:g} s) -> {} fitted ({})\n",
                 rows, logs.size(), bursts ? fmt::format(" -> {} burst means", samples) : "",
                 calibration.axes.front().in_sample.samples, first.pipeline.warm_up_seconds(),
                 calibration.axes.front().training_samples,
                 first.pipeline.decimation == 1 ? std::string("all") : fmt::format("one in {}", first.pipeline.decimation));
    }
  }
  print_axes(result, args.json,
             fmt::format("{} model written to {} (metrics in-sample, on the training data: optimistic)",
                         args.model, args.out));
  return 0;
}

}  // namespace

void add_fit_options(CLI::App& app, FitArguments& args, bool data_required) {
  args.data.add_to(app, data_required);
  std::vector<std::string> kinds;
  for (const ModelKind kind : kModelKinds) kinds.emplace_back(to_string(kind));
  app.add_option("--model", args.model, fmt::format("{} or {}", fmt::join(kinds.begin(), kinds.end() - 1, ", "), kinds.back()))
      ->check(CLI::IsMember(kinds));
  app.add_option("--C", args.C, "SVR penalty C")->check(kModelScale);
  app.add_option("--sigma", args.sigma, "RBF width σ, on standardized features")->check(kKernelWidth);
  app.add_option("--gamma", args.gamma, "RBF γ = 1/(2σ²) (libsvm's -g)")->check(kModelScale);
  app.add_option("--epsilon", args.epsilon, "SVR tube half-width, standardized target units (libsvm -p)")
      ->check(kNonNegative);
  app.add_option("--tol", args.tolerance, "SVR stopping tolerance (libsvm -e)")->check(kPositive);
  app.add_option("--rate-span", args.rate_span, "span of the dT/dt difference in seconds (default: --smooth)")
      ->check(kPositive);
  app.add_option("--decimate", args.decimate, "keep every Nth ready sample for fitting (default: ~10 per window)")
      ->check(whole_number(1, 1000000000));
  add_list_option(app, "--features", args.features, "feature terms (default dT,rate, the paper's; lag:TAU, lagrate:TAU, gradrate:TAU:TG, dir:TAU[:LAG[:R0]], grad:A-B, gradrate:A-B, hinge:TAU:K, lag2:T1:T2, lag2rate:T1:T2, nodehinge:T1:T2:TL:K, play:TAU:W, on:TAU, products, powers), or auto to choose them per axis by blocked CV; docs/features.md");
  add_identify_option(app, args.identify);
  app.add_option("--node-channel", args.node_channel,
                  "with --features auto and one --temp column per axis: look for each axis' thermal node on any "
                  "thermometer (any, default: another axis' may sit on its coil) or on its own only (own); "
                  "docs/features.md")
      ->check(CLI::IsMember({"own", "any"}))
      ->option_text("own|any");
  app.add_option("--log-start", args.log_start,
                 "with --features auto: the training logs start at power-on (power-on, default: the turn-on "
                 "transient and self-heating terms on:TAU are offered) or with the unit already running (running)")
      ->check(CLI::IsMember({"power-on", "running"}))
      ->option_text("power-on|running");
  app.add_option("--tune", args.tune, "tune C and σ per axis: afsa (default for svr), grid or random")
      ->check(CLI::IsMember({"afsa", "grid", "random"}));
  app.add_option("--objective", args.objective,
                  "tuning objective: cv (blocked k-fold, default), holdout (last 30 %), train (in-sample, optimistic)")
      ->check(CLI::IsMember({"cv", "holdout", "train"}));
  app.add_option("--evaluations", args.evaluations, "tuning budget per axis (default 49, a 7x7 grid's worth)")->check(kEvaluations);
  app.add_option("--folds", args.folds, "folds of the blocked cross-validation, 2 to 100 (default 5)")->check(whole_number(2, 100));
  app.add_option("--folds-by", args.folds_by,
                  "cross-validation folds of tuning and --features auto: time (default; --folds blocks in time, "
                  "over several --data files in order) or runs (with two or more --data files, one fold per "
                  "file: leave-one-run-out)")
      ->check(CLI::IsMember({"runs", "time"}));
  app.add_flag("--tune-epsilon", args.tune_epsilon, "tune ε as well");
  app.add_flag("--keep-kernel", args.keep_kernel,
               "with --model svr --features auto: keep the tuned kernel on the linear part's residual without "
               "judging it (by default a nested CV leaves it out unless it cuts the linear part's CV MSE by 10 %; "
               "docs/features.md)");
  app.add_option("--max-vectors", args.max_vectors,
                  "at most K support vectors per axis: the reduced set fitted to the SVR (as compress does)")
      ->check(whole_number(1, std::size_t{1} << 20));
  app.add_option("--kernel", args.kernel,
                 fmt::format("SVR kernel matrix: exact (SMO), nystrom (a low-rank factor of at most --landmarks "
                             "samples, for full-rate logs) or auto (default: up to {} samples per fit the exact fit, "
                             "through a factor of rank <= {} when the kernel matrix has one, by SMO otherwise; "
                             "nystrom beyond; docs/svr.md)",
                             SvrOptions{}.exact_limit, SvrOptions{}.low_rank_landmarks))
      ->check(CLI::IsMember({"auto", "exact", "nystrom"}))
      ->option_text("auto|exact|nystrom");
  app.add_option("--landmarks", args.landmarks, "with the Nyström kernel: the factor's largest rank (default 512)")
      ->check(whole_number(1, 100000));
  app.add_option("--seed", args.seed, "seed of the tuner's random choices")->check(kSeed);
  app.add_option("--threads", args.threads, "threads for tuning and the feature search (default: all cores); results do not depend on it")
      ->check(kThreads);
}

Command add_fit(CLI::App& parent) {
  auto args = std::make_shared<FitArguments>();
  CLI::App* app = parent.add_subcommand("fit", "fit one drift model per gyro axis");
  add_fit_options(*app, *args);
  app->add_option("--out", args->out, "model file to write")->required();
  app->add_flag("--json", args->json, "print one JSON object on stdout");
  return {app, [args, app] { return run_fit(*args, *app); }};
}

}  // namespace thermodrift::cli
