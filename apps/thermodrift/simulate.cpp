// thermodrift simulate: a 3-axis FOG chamber test with known true drift (docs/simulator.md).
#include <fmt/format.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "commands.hpp"
#include "interrupt.hpp"
#include "numbers.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/sim/law_family.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift::cli {

namespace {

struct SimulateArguments {
  sim::SimulatorOptions options;
  std::string out;
  std::optional<std::uint64_t> law;  // a unit of the law family instead of the default unit
  std::string profile = "cycle";
  std::optional<std::uint64_t> profile_seed;
  bool describe = false;
};

sim::ChamberRun simulate_law(const SimulateArguments& args, const StopToken& stop) {
  const sim::UnitLaw unit = sim::draw_unit(*args.law);
  const sim::Setpoint setpoint = sim::draw_profile(sim::parse_profile_kind(args.profile), unit,
                                                   args.profile_seed.value_or(*args.law), args.options.cycles);
  if (args.describe) fmt::print(stderr, "{}", unit.describe());
  sim::ChamberRun run = sim::simulate_unit(unit, setpoint, args.options.seed, args.options.rate_hz, stop);
  if (args.options.record_internal_states) {
    // The law's true regressors, the states its drift is linear in (coefficients: --describe).
    const auto names = sim::law_regressor_names();
    sim::LawRegressors regressors = sim::law_regressors(unit, setpoint, args.options.rate_hz);
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t k = 1; k < sim::kLawRegressors; ++k) {  // not the constant
        run.column_names.push_back(fmt::format("law_{}_{}", sim::kAxisNames[a], names[k]));
        run.columns.push_back(std::move(regressors[a][k]));
      }
    }
  }
  return run;
}

int run_simulate(const SimulateArguments& args) {
  std::string why;
  if (!args.options.IsValid(&why)) throw UsageError(why);
  const StopToken stop = interrupt_token();
  // Opened first, as fit and compensate do: an output that cannot be written is refused
  // before the simulation, and a FIFO's reader gets an end of file if it stops.
  AtomicFile out(args.out);
  const sim::ChamberRun run = args.law ? simulate_law(args, stop) : sim::simulate(args.options, stop);
  sim::write_csv(run, out.stream(), stop);
  out.commit();
  fmt::print(stderr, "thermodrift: wrote {} rows ({:.1f} h, {} cycle{}) to {}\n", run.rows(),
             static_cast<double>(run.rows()) / run.rate_hz / 3600.0, args.options.cycles,
             args.options.cycles == 1 ? "" : "s", args.out);
  return 0;
}

}  // namespace

Command add_simulate(CLI::App& parent) {
  auto args = std::make_shared<SimulateArguments>();
  CLI::App* app = parent.add_subcommand("simulate", "simulate a 3-axis FOG chamber test with known true drift");
  app->add_option("--out", args->out, "CSV file to write")->required();
  app->add_option("--seed", args->options.seed, "seed of every noise stream")->check(kSeed);
  app->add_option("--cycles", args->options.cycles, "number of chamber cycles")->check(whole_number(1, 1000));
  app->add_option("--rate", args->options.rate_hz, "sample rate in Hz")->check(kPositive);
  app->add_option("--min-temp", args->options.chamber_min_c, "cold extreme of the chamber, °C")->check(kCelsius);
  app->add_option("--max-temp", args->options.chamber_max_c, "hot extreme of the chamber, °C")->check(kCelsius);
  app->add_option("--ramp", args->options.ramp_rate_c_per_min, "chamber ramp rate, °C/min")
      ->check(kPositive);
  app->add_option("--soak", args->options.extreme_soak_min, "soak at each extreme, minutes")
      ->check(kNonNegative);
  app->add_option("--law", args->law,
                  "draw the unit from the law family with this seed (thermal network, drift law, noise; "
                  "docs/simulator.md) instead of the default unit")
      ->check(kSeed);
  app->add_option("--profile", args->profile, "with --law: cycle, slow, fast, staircase, partial or wander");
  app->add_option("--profile-seed", args->profile_seed, "with --law: seed of the programme (default: the law's)")
      ->check(kSeed);
  app->add_flag("--describe", args->describe, "with --law: print the drawn unit's law on stderr");
  app->add_flag("--internal-states", args->options.record_internal_states,
                "also write the coil temperature, gradient and hysteresis state of each axis (with --law: each "
                "axis' true drift regressors, law_<axis>_<name>)");
  return {app, [args, app] {
            // The default unit's programme, or a drawn law's: the other's options would be ignored.
            for (const char* option : args->law ? std::vector<const char*>{"--min-temp", "--max-temp", "--ramp", "--soak"}
                                                : std::vector<const char*>{"--profile", "--profile-seed", "--describe"}) {
              if (app->count(option) == 0) continue;
              throw UsageError(fmt::format(fmt::runtime(args->law ? "{} applies to the default unit, not --law" : "{} applies with --law"),
                                           option));
            }
            return run_simulate(*args);
          }};
}

}  // namespace thermodrift::cli
