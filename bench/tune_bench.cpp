// SVR tuning on a simulated chamber test: AFSA against grid and random search.
//
//   build/bin/tune_bench [--evaluations N] [--grid-evaluations N] [--threads N]
//                        [--objective cv|holdout|train] [--methods afsa,grid,random]
//                        [--search-tolerance T] [--search-max-iterations N] [--seed S]
//                        [--kernel auto|exact] [--low-rank-landmarks N] [--features paper|auto]
//   build/bin/tune_bench --points C:SIGMA,...
//
// The default simulated test (two chamber cycles, 1 Hz, three axes). For each axis the
// project's pipeline (smoothing 100 s, dT/dt over 100 s, every 10th sample) gives
// (ΔT, dT/dt) → smoothed gyro on cycle 1 (~2,270 samples); features and target are
// standardized; each method tunes (C, σ) by blocked 5-fold CV on cycle 1 only, the
// tuned point is refitted at the solver's normal tolerance on all of cycle 1, and the
// model predicts every ready sample of cycle 2. Prints per method and axis: the tuning
// objective and the held-out MSE in (°/h)², evaluations, fits (capped at the search's SMO
// step cap, solved through a low-rank factor), seconds; then totals. With --points, no
// tuning: each (C, σ) is fitted on all of cycle 1 as the search fits it (SMO with the
// search's tolerance and cap; the low-rank path) and by SMO to a 1e-5 tolerance, and the
// ε-SVR primal objective of each function is printed. With --features auto the inputs are
// the terms `fit --features auto` identifies on cycle 1 and the target their linear fit's
// residual (the partially linear SVR); with more than 16 of them AFSA also runs with every
// squared distance computed per column, for the ratio against the stored distances.
// docs/tuning.md has measured figures.
#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/svr_model.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "thermodrift/tune/calibration.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

using namespace thermodrift;

namespace {

// CPU seconds of the whole process (all threads): on a shared machine the wall clock
// says as much about the neighbours as about us; CPU / threads is the idle-machine wall.
double process_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

struct Arguments {
  long evaluations = 49;       // AFSA and random search
  long grid_evaluations = 49;  // 7 x 7
  int threads = 2;
  std::uint64_t seed = 1;
  TuneObjective objective = TuneObjective::cv;
  std::vector<TuneMethod> methods{TuneMethod::afsa, TuneMethod::grid, TuneMethod::random};
  double search_tolerance = -1;      // < 0: the library default
  long search_max_iterations = -1;   // < 0: the library default
  bool low_rank = true;              // --kernel auto (the default) or exact: SMO for every fit
  std::size_t low_rank_landmarks = 0;  // 0: the library default
  std::vector<std::pair<double, double>> points;  // --points C:sigma,...: the search's fits judged instead
  bool identified = false;  // --features auto: tune on the identified terms, as fit --model svr --features auto
};

Arguments parse(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        fmt::print(stderr, "{} needs a value\n", flag);
        std::exit(2);
      }
      return argv[++i];
    };
    if (flag == "--evaluations") args.evaluations = std::stol(value());
    else if (flag == "--grid-evaluations") args.grid_evaluations = std::stol(value());
    else if (flag == "--threads") args.threads = std::stoi(value());
    else if (flag == "--seed") args.seed = std::stoull(value());
    else if (flag == "--objective") args.objective = parse_tune_objective(value());
    else if (flag == "--search-tolerance") args.search_tolerance = std::stod(value());
    else if (flag == "--search-max-iterations") args.search_max_iterations = std::stol(value());
    else if (flag == "--kernel") args.low_rank = value() != "exact";
    else if (flag == "--features") {
      const std::string features = value();
      if (features != "auto" && features != "paper") {
        fmt::print(stderr, "--features takes auto or paper, not {}\n", features);
        std::exit(2);
      }
      args.identified = features == "auto";
    }
    else if (flag == "--low-rank-landmarks") args.low_rank_landmarks = std::stoul(value());
    else if (flag == "--points") {
      const std::string list = value();
      std::size_t begin = 0;
      while (begin < list.size()) {
        const std::size_t end = std::min(list.find(',', begin), list.size());
        const std::string point = list.substr(begin, end - begin);
        const std::size_t colon = point.find(':');
        if (colon == std::string::npos) {
          fmt::print(stderr, "--points: expected C:sigma, got '{}'\n", point);
          std::exit(2);
        }
        args.points.emplace_back(std::stod(point.substr(0, colon)), std::stod(point.substr(colon + 1)));
        begin = end + 1;
      }
    }
    else if (flag == "--methods") {
      args.methods.clear();
      const std::string list = value();
      std::size_t begin = 0;
      while (begin <= list.size()) {
        const std::size_t end = std::min(list.find(',', begin), list.size());
        args.methods.push_back(parse_tune_method(list.substr(begin, end - begin)));
        begin = end + 1;
      }
    } else {
      fmt::print(stderr, "unknown argument {}\n", flag);
      std::exit(2);
    }
  }
  return args;
}

ChamberLog to_log(const sim::ChamberRun& run) {
  ChamberLog log;
  log.source = "simulated";
  log.time = run.column("time_s");
  for (const char* axis : {"x", "y", "z"}) {
    log.gyro_names.push_back(fmt::format("gyro_{}", axis));
    log.gyro.push_back(run.column(fmt::format("gyro_{}", axis)));
    log.temperature_names.push_back(fmt::format("temp_{}", axis));
    log.temperature.push_back(run.column(fmt::format("temp_{}", axis)));
  }
  log.line.resize(log.time.size());
  for (std::size_t i = 0; i < log.line.size(); ++i) log.line[i] = i + 2;
  return log;
}

struct AxisData {
  FeatureTable training;  // cycle 1, decimated
  FeatureTable held_out;  // cycle 2, every ready sample
  Standardization scaling;
};

AxisData axis_data(const ChamberLog& training, const ChamberLog& held_out, std::size_t axis) {
  Pipeline pipeline;  // smoothing and rate span 100 s, terms (dT, rate)
  pipeline.decimation = 10;
  double sum = 0;
  for (double t : training.temperature[axis]) sum += t;
  pipeline.reference_temperature = sum / static_cast<double>(training.rows());
  AxisData data;
  data.training = build_feature_table(pipeline, training, axis, axis, true);
  data.held_out = build_feature_table(pipeline, held_out, axis, axis, false);
  data.scaling = Standardization::of(data.training.features, data.training.target);
  return data;
}

// As `fit --model svr --features auto` tunes: the terms the least-squares search chose on
// cycle 1 (tens of them: members averaged), the kernel's target the residual of their
// linear fit (the partially linear SVR), held out on cycle 2 the same way.
std::vector<AxisData> identified_axis_data(const ChamberLog& training, const ChamberLog& held_out) {
  CalibrationOptions options;
  options.terms = {"auto"};
  const Calibration linear = calibrate({training}, LogSpec{}, options);
  std::vector<AxisData> axes;
  for (std::size_t axis = 0; axis < linear.model.axes.size(); ++axis) {
    const AxisModel& model = linear.model.axes[axis];
    auto table_of = [&](const ChamberLog& log, bool training_rows) {
      FeatureTable table = build_feature_table(model.pipeline, log, axis, temperature_channel_per_axis(log).at(axis),
                                               training_rows);
      table.target -= model.predict(table.features);
      return table;
    };
    AxisData data;
    data.training = table_of(training, true);
    data.held_out = table_of(held_out, false);
    data.scaling = Standardization::of(data.training.features, data.training.target);
    axes.push_back(std::move(data));
  }
  return axes;
}

struct Row {
  double objective_dph2 = 0;
  double held_out_mse = 0;
  long evaluations = 0;
  long fits = 0;
  long capped = 0;
  long low_rank = 0;
  double seconds = 0;
  double cpu_seconds = 0;
  double C = 0, sigma = 0;
  double converged_dph2 = 0;  // the CV objective at the tuned point with every fit converged
};

Row run_method(const AxisData& data, TuneMethod method, const Arguments& args, bool low_rank,
               bool store_distances = true) {
  SvrTuningOptions options;
  if (!store_distances) options.distance_budget_mb = 0;
  options.method = method;
  options.objective = args.objective;
  options.evaluations = method == TuneMethod::grid ? args.grid_evaluations : args.evaluations;
  options.threads = args.threads;
  options.seed = args.seed;
  if (args.search_tolerance >= 0) options.search_tolerance = args.search_tolerance;
  if (args.search_max_iterations >= 0) options.search_max_iterations = args.search_max_iterations;
  options.solver.approximation = low_rank ? SvrApproximation::automatic : SvrApproximation::exact;
  if (args.low_rank_landmarks > 0) options.solver.low_rank_landmarks = args.low_rank_landmarks;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  const Eigen::MatrixXd samples = data.scaling.features(data.training.features);
  const Eigen::VectorXd targets = data.scaling.target(data.training.target);
  const SvrTuningResult tuned = tune_svr(samples, targets, options);
  // The final fit at the solver's normal tolerance and cap, on all of cycle 1.
  SvrModel model;
  model.scaling = data.scaling;
  model.function = SvrTrainer(tuned.solver).train(samples, targets).function;
  const Eigen::VectorXd predicted = model.predict(data.held_out.features);
  Row row;
  const double scale2 = data.scaling.target_scale * data.scaling.target_scale;
  row.objective_dph2 = tuned.objective_value * scale2;
  row.held_out_mse = (predicted - data.held_out.target).squaredNorm() / static_cast<double>(predicted.size());
  row.evaluations = tuned.evaluations;
  row.fits = tuned.fits;
  row.capped = tuned.capped_fits;
  row.low_rank = tuned.low_rank_fits;
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  row.cpu_seconds = process_cpu_seconds() - cpu_start;
  row.C = tuned.C;
  row.sigma = tuned.sigma;
  // What the search's figure stands for: the same CV at the tuned point, every fit
  // converged (SMO to 1e-5, or exact through the low-rank factor where that holds it).
  SvrTuningOptions converged = options;
  converged.search_tolerance = 1e-5;
  converged.search_max_iterations = 5'000'000;
  converged.solver.approximation = SvrApproximation::automatic;
  row.converged_dph2 = SvrObjective(samples, targets, converged)(tuned.C, tuned.sigma, tuned.epsilon) * scale2;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const Arguments args = parse(argc, argv);
  const sim::SimulatorOptions sim_options;  // two cycles: train on the first, test on the second
  const sim::ChamberRun run = sim::simulate(sim_options);
  const ChamberLog log = to_log(run);
  const std::size_t split = run.cycle_start_rows().back();
  const ChamberLog training = slice_rows(log, 0, split);
  const ChamberLog held_out = slice_rows(log, split, log.rows());
  const auto floor = run.noise_floor(100);

  std::vector<AxisData> axes;
  if (args.identified) {
    axes = identified_axis_data(training, held_out);
  } else {
    for (std::size_t a = 0; a < 3; ++a) axes.push_back(axis_data(training, held_out, a));
  }
  fmt::print("tune_bench: simulated 2-cycle chamber test, train cycle 1 ({} / {} / {} samples), "
             "held out cycle 2; objective {}, {} threads\n",
             axes[0].training.rows(), axes[1].training.rows(), axes[2].training.rows(), to_string(args.objective),
             args.threads);
  if (args.identified) {
    fmt::print("features: the terms --features auto identified on cycle 1 ({} / {} / {}), the target their linear "
               "fit's residual\n",
               axes[0].training.features.cols(), axes[1].training.features.cols(), axes[2].training.features.cols());
  }
  fmt::print("noise floor after 100 s smoothing, (°/h)²: x {:.3g}  y {:.3g}  z {:.3g}\n\n", floor[0], floor[1],
             floor[2]);
  fmt::print("{:<18} {:<4} {:>10} {:>9} {:>12} {:>12} {:>12} {:>6} {:>6} {:>7} {:>8} {:>8} {:>8}\n", "method", "axis", "C",
             "sigma", "tune MSE", "converged", "held-out MSE", "evals", "fits", "capped", "low-rank", "seconds", "cpu s");
  const char* names[] = {"x", "y", "z"};
  if (!args.points.empty()) {
    // Each point fitted on all of cycle 1 three ways; the ε-SVR primal objective of each
    // function says how far from the optimum the search's fits are.
    fmt::print("primal objective ½‖f‖² + C·Σ max(0, |y − f| − ε) on cycle 1 (ε = 0.01), and seconds:\n");
    fmt::print("{:<4} {:>8} {:>7} {:>26} {:>30} {:>26}\n", "axis", "C", "sigma", "search SMO (capped)",
               "search low-rank (landmarks)", "SMO to 1e-5");
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const Eigen::MatrixXd samples = axes[a].scaling.features(axes[a].training.features);
      const Eigen::VectorXd targets = axes[a].scaling.target(axes[a].training.target);
      const SvrTuningOptions defaults;
      for (const auto& [C, sigma] : args.points) {
        SvrOptions search;
        search.C = C;
        search.gamma = gamma_of_sigma(sigma);
        search.epsilon = defaults.epsilon;
        search.tolerance = defaults.search_tolerance;
        search.max_iterations = defaults.search_max_iterations;
        search.approximation = SvrApproximation::exact;
        SvrOptions low_rank = search;
        low_rank.approximation = SvrApproximation::low_rank;
        SvrOptions converged = search;
        converged.tolerance = 1e-5;
        converged.max_iterations = 50'000'000;
        auto run = [&](const SvrOptions& options) {
          const SvrFit fit = SvrTrainer(options).train(samples, targets);
          const bool factored = fit.summary.approximation == SvrApproximation::nystrom;
          return fmt::format("{:.7g} {:.3f} s{}", fit.function.primal_objective(samples, targets, C, search.epsilon),
                             fit.summary.seconds,
                             factored ? fmt::format(" ({})", fit.summary.landmarks)
                                      : fit.summary.termination == SvrTermination::converged ? "" : " capped");
        };
        fmt::print("{:<4} {:>8.4g} {:>7.4g} {:>26} {:>30} {:>26}\n", names[a], C, sigma, run(search), run(low_rank),
                   run(converged));
        std::fflush(stdout);
      }
    }
    return 0;
  }
  // Each method as asked; AFSA once more with every fit by SMO (`--kernel exact`, the state before
  // the low-rank fits, docs/tuning.md) for the ratio, in the same run; with more terms than
  // SvrTuningOptions::kDistanceFeatures, AFSA once more with every distance computed per
  // column (distance_budget_mb = 0, the state before stored distances).
  struct Run {
    TuneMethod method;
    bool low_rank;
    bool store_distances;
  };
  std::vector<Run> runs;
  for (const TuneMethod method : args.methods) runs.push_back({method, args.low_rank, true});
  bool wide = false;
  for (const auto& axis : axes) wide = wide || axis.training.features.cols() > SvrTuningOptions::kDistanceFeatures;
  for (const TuneMethod method : args.methods) {
    if (method == TuneMethod::afsa && args.low_rank) runs.push_back({method, false, true});
    if (method == TuneMethod::afsa && wide) runs.push_back({method, args.low_rank, false});
  }
  double afsa_cpu[2] = {0, 0}, afsa_wall[2] = {0, 0};
  double computed_cpu = 0, computed_wall = 0, stored_cpu = 0, stored_wall = 0;
  std::vector<Row> stored_rows;
  bool same_points = true;
  for (const auto& [method, low_rank, store_distances] : runs) {
    const std::string label = fmt::format("{}{}{}", to_string(method), low_rank ? "" : " (SMO only)",
                                          store_distances ? "" : " (d² computed)");
    Row total;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const Row row = run_method(axes[a], method, args, low_rank, store_distances);
      if (method == TuneMethod::afsa && low_rank == args.low_rank) {
        if (store_distances) {
          stored_rows.push_back(row);
        } else {
          same_points = same_points && row.C == stored_rows.at(a).C && row.sigma == stored_rows.at(a).sigma &&
                        row.objective_dph2 == stored_rows.at(a).objective_dph2;
        }
      }
      fmt::print("{:<18} {:<4} {:>10.4g} {:>9.4g} {:>12.4g} {:>12.4g} {:>12.4g} {:>6} {:>6} {:>7} {:>8} {:>8.2f} {:>8.2f}\n",
                 label, names[a], row.C, row.sigma, row.objective_dph2, row.converged_dph2, row.held_out_mse,
                 row.evaluations, row.fits, row.capped, row.low_rank, row.seconds, row.cpu_seconds);
      total.objective_dph2 += row.objective_dph2;
      total.converged_dph2 += row.converged_dph2;
      total.held_out_mse += row.held_out_mse;
      total.evaluations += row.evaluations;
      total.fits += row.fits;
      total.capped += row.capped;
      total.low_rank += row.low_rank;
      total.seconds += row.seconds;
      total.cpu_seconds += row.cpu_seconds;
    }
    fmt::print("{:<18} {:<4} {:>10} {:>9} {:>12.4g} {:>12.4g} {:>12.4g} {:>6} {:>6} {:>7} {:>8} {:>8.2f} {:>8.2f}\n\n",
               label, "all", "", "", total.objective_dph2, total.converged_dph2, total.held_out_mse,
               total.evaluations, total.fits, total.capped, total.low_rank, total.seconds, total.cpu_seconds);
    if (method == TuneMethod::afsa && !store_distances) {
      computed_cpu = total.cpu_seconds;
      computed_wall = total.seconds;
    } else if (method == TuneMethod::afsa) {
      afsa_cpu[low_rank ? 1 : 0] = total.cpu_seconds;
      afsa_wall[low_rank ? 1 : 0] = total.seconds;
      if (low_rank == args.low_rank) {
        stored_cpu = total.cpu_seconds;
        stored_wall = total.seconds;
      }
    }
    std::fflush(stdout);
  }
  if (afsa_cpu[0] > 0 && afsa_cpu[1] > 0) {
    fmt::print("afsa, low-rank fits against SMO only: {:.2f}x less CPU ({:.2f} → {:.2f} s), "
               "{:.2f}x less wall time ({:.2f} → {:.2f} s)\n",
               afsa_cpu[0] / afsa_cpu[1], afsa_cpu[0], afsa_cpu[1], afsa_wall[0] / afsa_wall[1], afsa_wall[0],
               afsa_wall[1]);
  }
  if (computed_cpu > 0 && stored_cpu > 0) {
    fmt::print("afsa, stored squared distances against computed per column: {:.2f}x less CPU ({:.2f} → {:.2f} s), "
               "{:.2f}x less wall time ({:.2f} → {:.2f} s); tuned C, σ and CV MSE {}\n",
               computed_cpu / stored_cpu, computed_cpu, stored_cpu, computed_wall / stored_wall, computed_wall,
               stored_wall, same_points ? "identical" : "DIFFERENT");
  }
  return 0;
}
