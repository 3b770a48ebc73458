// thermodrift demo: the main job on the built-in default — a simulated 3-axis FOG over
// two chamber cycles, every model fitted on the first cycle and judged on the second.
#include <fmt/format.h>

#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/report/study.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::cli {

namespace {

struct DemoArguments {
  std::string out = "thermodrift-demo";
  std::uint64_t seed = 1;
};

void print_table(const Study& study, const std::array<double, 3>& floor, bool held_out) {
  fmt::print("\n{} — residual MSE of the smoothed drift, (°/h)²\n",
             held_out ? "HELD-OUT (second cycle, never seen in fitting)" : "IN-SAMPLE (first cycle, as the paper reports)");
  fmt::print("{:<8} {:>12}", "axis", "original");
  for (const auto& m : study.models) fmt::print(" {:>12}", m.model);
  fmt::print(" {:>12}\n", "noise floor");
  const auto axes = study.models.front().in_sample.size();
  for (std::size_t a = 0; a < axes; ++a) {
    const auto& first = held_out ? study.models.front().held_out[a] : study.models.front().in_sample[a];
    fmt::print("{:<8} {:>12.4g}", study.models.front().calibration.model.axes[a].name, first.mse_before);
    for (const auto& m : study.models) {
      fmt::print(" {:>12.4g}", (held_out ? m.held_out[a] : m.in_sample[a]).mse_after);
    }
    fmt::print(" {:>12.4g}\n", a < floor.size() ? floor[a] : 0.0);
  }
}

int run_demo(const DemoArguments& args) {
  std::filesystem::create_directories(args.out);
  sim::SimulatorOptions sim_options;
  sim_options.seed = args.seed;
  fmt::print(stderr, "thermodrift demo: simulating a 3-axis FOG, {} chamber cycles over {:g}..{:g} °C at {:g} °C/min\n",
             sim_options.cycles, sim_options.chamber_min_c, sim_options.chamber_max_c, sim_options.ramp_rate_c_per_min);
  const sim::ChamberRun run = sim::simulate(sim_options);
  const std::string log_path = (std::filesystem::path(args.out) / "chamber.csv").string();
  {
    AtomicFile file(log_path);
    sim::write_csv(run, file.stream());
    file.commit();
  }
  LogSpec spec;
  spec.time_column = "time_s";
  spec.gyro_columns = {"gyro_x", "gyro_y", "gyro_z"};
  spec.temperature_columns = {"temp_x", "temp_y", "temp_z"};
  const ChamberLog log = read_chamber_log(log_path, spec);

  StudyOptions options;
  options.split_row = run.cycle_start_rows().back();
  options.progress = [](const std::string& line) { fmt::print(stderr, "thermodrift demo: {}\n", line); };
  Study study = run_study(log, spec, options);
  study.split_description = "trained on cycle 1, held out: cycle 2";
  const auto floor = run.noise_floor(options.calibration.smooth_seconds);

  print_table(study, floor, false);
  print_table(study, floor, true);
  const std::string summary = (std::filesystem::path(args.out) / "summary.json").string();
  write_file_atomically(summary, study.to_json().dump(1) + "\n");
  fmt::print("\nlog: {}\nsummary: {}\n", log_path, summary);
  return 0;
}

}  // namespace

Command add_demo(CLI::App& parent) {
  auto args = std::make_shared<DemoArguments>();
  CLI::App* app = parent.add_subcommand("demo", "the seed's study on a simulated two-cycle chamber test");
  app->add_option("--out", args->out, "folder for the log, models and report (default thermodrift-demo)");
  app->add_option("--seed", args->seed, "simulator seed");
  return {app, [args] { return run_demo(*args); }};
}

}  // namespace thermodrift::cli
