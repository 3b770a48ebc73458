// thermodrift report: the paper's whole study on a user's log, as DIR/report.html and
// DIR/summary.json (docs/report.md).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "report_command.hpp"
#include "lists.hpp"
#include "numbers.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/io/csv_reader.hpp"
#include "thermodrift/io/time_stamp.hpp"
#include "thermodrift/sim/chamber_run.hpp"
#include "thermodrift/report/report.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift::cli {

namespace {

struct ReportArguments {
  std::vector<std::string> features;  // besides the paper's pair; empty: the pair only
  FeatureSelectionOptions::Method identify = FeatureSelectionOptions{}.method;
  DataOptions data;
  std::string out;
  std::optional<double> holdout_fraction;
  std::optional<std::string> split_time;
  std::uint64_t seed = 1;
  int threads = 1;
  long evaluations = 100;
};

// The true drift, when the log carries it (as thermodrift simulate writes it): the
// simulator names its columns, the header says whether they are there.
std::vector<std::vector<double>> read_true_drift(const std::string& file, const LogSpec& spec, const ChamberLog& log) {
  const auto columns = sim::true_drift_columns(log.gyro_names);
  if (!columns) return {};
  const CsvReader reader(file);
  const auto& header = reader.header();
  for (const auto& name : *columns) {
    if (std::find(header.begin(), header.end(), name) == header.end()) return {};
  }
  LogSpec drift_spec = spec;
  drift_spec.gyro_columns = *columns;
  ChamberLog drift = read_chamber_log(file, drift_spec);
  if (drift.rows() != log.rows()) return {};
  return drift.gyro;
}

int run_report(const ReportArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  if (args.data.files.size() != 1) throw UsageError("report reads one log (--data FILE)");
  check_output_folder(args.out);  // before the log is read and the study run; write_report stages it
  const LogSpec spec = args.data.spec();
  const ChamberLog log = args.data.read(spec, args.data.warm_up_seconds(), interrupt_token()).front();
  ReportOptions options =
      paper_report_options(args.seed, args.threads, args.evaluations, args.identify, args.features, interrupt_token());
  options.out_dir = args.out;
  options.study.calibration.smooth_seconds = args.data.smooth;
  if (args.split_time) {
    options.study.split_row = row_at_time(log, *args.split_time);
    options.study.split_description = fmt::format("held out from t = {} on (--split-time)",
                                                  looks_like_iso_8601(*args.split_time) ? *args.split_time
                                                                                        : *args.split_time + " s");
  } else if (args.holdout_fraction) {
    if (!(*args.holdout_fraction > 0 && *args.holdout_fraction < 1)) {
      throw UsageError(fmt::format("--holdout-fraction {} is not in (0, 1)", *args.holdout_fraction));
    }
    options.study.holdout_fraction = *args.holdout_fraction;
  }
  options.true_drift = read_true_drift(args.data.files.front(), spec, log);
  options.title = "thermodrift report — " + log.source;
  options.command_line = fmt::format("thermodrift report --data {} --out {}", log.source, args.out);
  if (!args.features.empty()) options.command_line += fmt::format(" --features {}", fmt::join(args.features, ","));
  if (args.identify == FeatureSelectionOptions::Method::greedy) options.command_line += " --identify greedy";
  options.earlier_steps.emplace_back(
      "read the log", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  options.progress = progress_printer("thermodrift report", start);
  const ReportResult result = write_report(log, spec, options);
  print_report_tables(result.summary);
  for (const auto& model : result.study.models) {
    for (std::size_t a = 0; a < model.calibration.model.axes.size(); ++a) {
      for (const auto& warning : fit_warnings(model.calibration.model.axes[a], model.in_sample[a])) {
        warn(fmt::format("{} ({}): {}", model.model, model.features, warning));
      }
    }
  }
  for (const auto& warning : result.summary.at("warnings")) warn(warning.get<std::string>());
  if (!result.figures_drawn) warn(result.figures_note);
  fmt::print("\nreport: {}\nsummary: {}\n", result.html_path, result.summary_path);
  return 0;
}

}  // namespace

std::function<void(const std::string&)> progress_printer(const std::string& prefix,
                                                         std::chrono::steady_clock::time_point start) {
  return [prefix, start](const std::string& line) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print(stderr, "{} [{:6.1f} s] {}\n", prefix, seconds, line);
  };
}

void print_report_tables(const nlohmann::json& summary) {
  const bool floor_known = summary["data"]["true_drift_known"].get<bool>();
  for (const char* part : {"in_sample", "held_out"}) {
    const auto& table = summary["tables"][part];
    fmt::print("\n{} — residual MSE of the smoothed drift, (°/h)²{}\n",
               std::string(part) == "in_sample" ? "IN-SAMPLE (training part, as the paper reports)"
                                                : "HELD-OUT (" + summary["split"]["description"].get<std::string>() + ")",
               floor_known ? "; [×floor] in brackets" : "");
    fmt::print("{:<10} {:>11}", "axis", "original");
    for (const auto& column : table["columns"]) fmt::print(" {:>22}", column["label"].get<std::string>());
    if (floor_known) fmt::print(" {:>11}", "noise floor");
    fmt::print("\n");
    for (const auto& row : table["rows"]) {
      fmt::print("{:<10} {:>11}", row["axis"].get<std::string>(), format_number(row["original_mse"].get<double>()));
      for (const auto& cell : row["models"]) {
        std::string text = format_number(cell["mse"].get<double>());
        if (floor_known && cell["ratio_to_floor"].is_number()) {
          text += " [" + format_number(cell["ratio_to_floor"].get<double>()) + "]";
        }
        fmt::print(" {:>22}", text);
      }
      if (floor_known && row["noise_floor"].is_number()) fmt::print(" {:>11}", format_number(row["noise_floor"].get<double>()));
      fmt::print("\n");
    }
  }
  // Where a partially linear SVR's kernel was left out, its column is its linear part's.
  bool first = true;
  for (const auto& entry : summary.value("feature_selection", nlohmann::json::array())) {
    for (const auto& chosen : entry["chosen"]) {
      if (!chosen.contains("kernel_check")) continue;
      if (first) fmt::print("\n");
      first = false;
      fmt::print("{}, {} on the chosen terms: kernel {}\n", entry["axis"].get<std::string>(),
                 chosen["label"].get<std::string>(), kernel_check_text(chosen["kernel_check"]));
    }
  }
}

Command add_report(CLI::App& parent) {
  auto args = std::make_shared<ReportArguments>();
  CLI::App* app = parent.add_subcommand("report", "the paper's study on a log: tables, figures, report.html, summary.json");
  args->data.add_to(*app);
  app->add_option("--out", args->out, "folder for report.html, summary.json, figures and models")->required();
  auto* fraction = app->add_option_function<double>(
      "--holdout-fraction", [args](double f) { args->holdout_fraction = f; },
      "the last fraction of the log held out (default 0.3)");
  app->add_option_function<std::string>("--split-time", [args](const std::string& s) { args->split_time = s; },
                                        "hold out the log from this time on: s on its clock, or an ISO 8601 stamp")
      ->excludes(fraction);
  app->add_option("--seed", args->seed, "seed of every random choice (recorded in the report)")->check(kSeed);
  add_list_option(*app, "--features", args->features, "feature terms to compare with the paper's dT,rate (e.g. auto, or lag:600,lagrate:600); docs/features.md");
  add_identify_option(*app, args->identify);
  app->add_option("--threads", args->threads, "threads for the SVR fits")->check(kThreads);
  app->add_option("--evaluations", args->evaluations, "AFSA budget of objective evaluations per axis (default 100)")
      ->check(kEvaluations);
  return {app, [args, app] {
            check_identify(*app, args->features);
            return run_report(*args);
          }};
}

}  // namespace thermodrift::cli
