// thermodrift evaluate: residual metrics of a model on a log it may not have seen.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <string_view>

#include "commands.hpp"
#include "evaluate_command.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "output.hpp"
#include "numbers.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift::cli {

namespace {

struct EvaluateArguments {
  DataOptions data;
  std::string model_file;
  double settle = 0;
  std::optional<std::string> log_start;  // --log-start; estimated when not given
  bool json = false;
};

// The keys every evaluate result starts with.
nlohmann::json evaluation_header(const std::string& model_file, double settle, LogStart start) {
  return {{"command", "evaluate"},
          {"model_file", model_file},
          {"evaluation", "on the given logs (held-out if the model was not fitted on them)"},
          {"settle_seconds", settle},
          {"log_start", log_start_name(start)}};
}

}  // namespace

nlohmann::json evaluation_result(const DriftModel& model, const std::string& model_file,
                                 const std::vector<ChamberLog>& logs, double settle, const StopToken& stop,
                                 LogStart start) {
  const std::vector<AxisEvaluation> evaluations = evaluate_axes(model, logs, settle, stop, start);
  double longest = 0;
  bool turn_on = false;  // an on:TAU term: the log's start is taken as power-on
  for (const auto& axis : model.axes) {
    longest = std::max(longest, axis.pipeline.longest_delay());
    const auto& terms = axis.pipeline.terms;
    turn_on = turn_on || std::any_of(terms.begin(), terms.end(), [](const FeatureTerm& term) {
                return term.has(FeatureAtom::Kind::turn_on);
              });
  }
  // A log cut from a longer recording starts the lags where the unit was not; judged within
  // the recording, they run through what came before. On development laws 1-40's next cycle
  // (docs/generalization.md, "A log cut from a running recording") the 90th percentile over
  // all axes was 22.8 times the floor with the lags started in equilibrium, 10.7 with them
  // carried over, and 13.5 with the cut cycle alone under --log-start running.
  constexpr std::string_view whole =
      "; a log cut from a longer recording is better judged within it: the whole recording with --settle up to "
      "the part to judge (or, with the cut log alone, --log-start running)";
  if (start == LogStart::running) {
    // The lags start where a ramp history leaves them: no equilibrium to warn about.
  } else if (settle == 0 && longest > 0) {
    warn(fmt::format("the model's lags (longest {:g} s) start in equilibrium at the start of the log{}; if it starts "
                     "mid-transient, --settle {:g} leaves the first {:g} s out of the metrics (and estimates the "
                     "log's start from them){}",
                     longest, turn_on ? ", and its on:TAU terms take that start as power-on" : "", 3 * longest,
                     3 * longest, whole));
  } else if (settle < 3 * longest) {
    warn(fmt::format("--settle {:g} is less than three times the model's slowest lag ({:g} s): if a log starts "
                     "mid-transient, its start still weighs on the metrics (by e^-{:.1f} of the lag's error there); "
                     "--settle {:g} leaves it out{}",
                     settle, longest, settle / longest, 3 * longest, whole));
  }
  nlohmann::json result = evaluation_header(model_file, settle, start);
  nlohmann::json axes = nlohmann::json::array();
  for (std::size_t a = 0; a < evaluations.size(); ++a) {
    const auto& axis = model.axes[a];
    nlohmann::json entry = evaluations[a].metrics.to_json();
    entry["name"] = axis.name;
    entry["model"] = axis.kind;
    if (start == LogStart::estimated) entry["running_weight"] = evaluations[a].running_weight;
    if (const auto& outside = evaluations[a].outside_envelope) {
      entry["outside_envelope"] = outside->outside;
      entry["outside_envelope_fraction"] = outside->outside_fraction();
      entry["outside_envelope_by_limit"] = {
          {"temperature", outside->temperature()}, {"rate", outside->rate()}, {"direction", outside->direction()}};
      if (outside->outside > 0) {
        warn(fmt::format("{}: {} of {} samples outside the training envelope ({}): the model extrapolates there",
                         axis.name, outside->outside, outside->samples, outside->describe(*axis.envelope)));
      }
    }
    if (!logs.empty() && axis.pipeline.smooth_seconds > 0) {
      add_noise_floor(entry, estimate_noise_floor(logs, a, axis.pipeline.smooth_seconds));
    }
    axes.push_back(entry);
  }
  result["axes"] = axes;
  if (logs.size() >= 2) {  // several runs: each on its own, then all together (above)
    nlohmann::json runs = nlohmann::json::array();
    for (const auto& log : logs) {
      const auto per_run = evaluate_axes(model, {log}, settle, stop, start);
      nlohmann::json run_axes = nlohmann::json::array();
      for (std::size_t a = 0; a < per_run.size(); ++a) {
        nlohmann::json entry = per_run[a].metrics.to_json();
        entry["name"] = model.axes[a].name;
        if (model.axes[a].pipeline.smooth_seconds > 0) {
          add_noise_floor(entry, estimate_noise_floor({log}, a, model.axes[a].pipeline.smooth_seconds));
        }
        run_axes.push_back(entry);
      }
      runs.push_back({{"file", log.source}, {"axes", run_axes}});
    }
    result["runs"] = runs;
  }
  return result;
}

namespace {

// The libsvm-format log: metrics only (no pipeline, no envelope, no noise floor).
nlohmann::json evaluate_libsvm_file(const DriftModel& model, const std::string& file) {
  nlohmann::json entry = evaluate_libsvm(model, read_libsvm(file, interrupt_token()), file).to_json();
  entry["name"] = model.axes.front().name;
  entry["model"] = model.axes.front().kind;
  return nlohmann::json::array({entry});
}

int run_evaluate(const EvaluateArguments& args) {
  const DriftModel model = load_drift_model(args.model_file);
  nlohmann::json result;
  if (args.data.format == "libsvm") {
    if (args.data.files.size() != 1) throw UsageError("--format libsvm takes one --data file");
    if (args.log_start && *args.log_start != "power-on") {
      throw UsageError(fmt::format("--log-start {} needs logs in time, not --format libsvm", *args.log_start));
    }
    result = evaluation_header(args.model_file, args.settle, LogStart::power_on);
    result["axes"] = evaluate_libsvm_file(model, args.data.files.front());
  } else {
    double warm_up = 0;
    for (const auto& axis : model.axes) warm_up = std::max(warm_up, axis.pipeline.warm_up_seconds());
    const auto logs = args.data.read(args.data.spec_for(model), warm_up, interrupt_token());
    result = evaluation_result(model, args.model_file, logs, args.settle, interrupt_token(),
                               parse_log_start(args.log_start.value_or("estimated")));
  }
  print_axes(result, args.json, fmt::format("{} on {}", args.model_file, fmt::join(args.data.files, ", ")));
  return 0;
}

}  // namespace

Command add_evaluate(CLI::App& parent) {
  auto args = std::make_shared<EvaluateArguments>();
  CLI::App* app = parent.add_subcommand("evaluate", "residual metrics of a model on a log");
  app->add_option("--model", args->model_file, "model file written by fit")->required()->check(CLI::ExistingFile);
  args->data.add_to(*app);
  app->add_option("--settle", args->settle,
                  "leave the first SECONDS of each log (and after each gap) out of the metrics, while lags settle")
      ->check(kNonNegative);
  app->add_option("--log-start", args->log_start,
                  "where each log starts: at power-on (power-on: the lags start in equilibrium at its first row), "
                  "cut from a running recording (running: each thermometer's initial line, held within its range, "
                  "runs for 6 h before the log, and --settle counts from its first row), or between the two as the "
                  "--settle rows, which are not judged, say (estimated, the default: per axis and log, the weight of "
                  "running's prediction in [0, 1] that fits them best; without --settle, power-on)")
      ->check(CLI::IsMember({"power-on", "running", "estimated"}))
      ->option_text("power-on|running|estimated");
  app->add_flag("--json", args->json, "print one JSON object on stdout");
  return {app, [args] { return run_evaluate(*args); }};
}

}  // namespace thermodrift::cli
