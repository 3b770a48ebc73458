// thermodrift demo: the main job on the built-in default — a simulated 3-axis FOG over
// two chamber cycles (-40..60 °C, 1 °C/min, 1 Hz), every model fitted on the first
// cycle and judged on the second, written up as DIR/report.html.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <chrono>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "report_command.hpp"
#include "lists.hpp"
#include "numbers.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/report/report.hpp"
#include "thermodrift/tune/svr_tuning.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::cli {

namespace {

struct DemoArguments {
  std::vector<std::string> features;  // besides the paper's pair; empty: the pair only
  FeatureSelectionOptions::Method identify = FeatureSelectionOptions{}.method;
  std::string out = "thermodrift-demo";
  std::uint64_t seed = 1;
  int threads = 2;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int run_demo(const DemoArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  const auto progress = progress_printer("thermodrift demo", start);
  StagedFolder out(args.out);
  const StopToken stop = interrupt_token();
  sim::SimulatorOptions sim_options;
  sim_options.seed = args.seed;
  progress(fmt::format("simulating a 3-axis FOG, {} chamber cycles over {:g}..{:g} °C at {:g} °C/min, {:g} Hz",
                       sim_options.cycles, sim_options.chamber_min_c, sim_options.chamber_max_c,
                       sim_options.ramp_rate_c_per_min, sim_options.rate_hz));
  const sim::ChamberRun run = sim::simulate(sim_options);
  stop.throw_if_requested("simulation");
  const std::string staged_log_path = (std::filesystem::path(out.staging()) / "chamber.csv").string();
  const std::string log_path = out.committed_path(staged_log_path);
  {
    AtomicFile file(staged_log_path);
    sim::write_csv(run, file.stream());
    file.commit();
  }
  stop.throw_if_requested("writing the log");
  const double simulate_seconds = seconds_since(start);
  const auto read_start = std::chrono::steady_clock::now();
  const LogSpec spec = sim::log_spec();
  ChamberLog log = read_chamber_log(staged_log_path, spec);
  log.source = log_path;  // as the report and the model files name it
  progress(fmt::format("wrote and read {} ({} rows)", log_path, log.rows()));

  ReportOptions options = paper_report_options(args.seed, args.threads, SvrTuningOptions{}.evaluations,
                                               args.identify, args.features, stop);
  options.out_dir = out.staging();
  options.study.split_row = run.cycle_start_rows().back();
  options.study.split_description = fmt::format("fitted on chamber cycle 1, held out: cycle 2 (from t = {:g} s)",
                                                run.cycle_start_rows().back() / run.rate_hz);
  options.title = "thermodrift demo — simulated 3-axis FOG, two chamber cycles";
  options.command_line = fmt::format("thermodrift demo --out {} --seed {}", args.out, args.seed);
  if (!args.features.empty()) options.command_line += fmt::format(" --features {}", fmt::join(args.features, ","));
  if (args.identify == FeatureSelectionOptions::Method::greedy) options.command_line += " --identify greedy";
  for (const std::string_view name : sim::drift_columns) options.true_drift.push_back(run.column(name));
  options.earlier_steps = {{"simulate and write the log", simulate_seconds}, {"read the log", seconds_since(read_start)}};
  options.progress = progress;
  // The default split would be the last 30 %; the demo holds out the whole second cycle.
  ReportResult result = write_report(log, spec, options);
  out.commit();
  print_report_tables(result.summary);
  for (const auto& warning : result.summary.at("warnings")) {
    fmt::print(stderr, "thermodrift demo: warning: {}\n", warning.get<std::string>());
  }
  if (!result.figures_drawn) fmt::print(stderr, "thermodrift demo: warning: {}\n", result.figures_note);
  fmt::print("\nlog:     {}\nreport:  {}\nsummary: {}\n", log_path, out.committed_path(result.html_path),
             out.committed_path(result.summary_path));
  progress("done");
  return 0;
}

}  // namespace

Command add_demo(CLI::App& parent) {
  auto args = std::make_shared<DemoArguments>();
  CLI::App* app = parent.add_subcommand("demo", "the paper's study on a simulated two-cycle chamber test, as an HTML report");
  app->add_option("--out", args->out, "folder for the log, models and report (default thermodrift-demo)");
  app->add_option("--seed", args->seed, "simulator seed")->check(kSeed);
  add_list_option(*app, "--features", args->features, "feature terms to compare with the paper's dT,rate (e.g. auto, or lag:600,lagrate:600); docs/features.md");
  add_identify_option(*app, args->identify);
  app->add_option("--threads", args->threads, "threads for the SVR fits (default 2)")->check(kThreads);
  return {app, [args, app] {
            check_identify(*app, args->features);
            return run_demo(*args);
          }};
}

}  // namespace thermodrift::cli
