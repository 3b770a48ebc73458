// Accuracy on drift laws nobody tuned on: the law family's units (sim/law_family.hpp),
// calibrated on one chamber cycle, judged on the next cycle and on two other profiles.
//
//   build/bin/generalization_bench [--seeds acceptance|development|S,S,...] [--limit N]
//                                  [--methods paper,linear,stepwise,svr,oracle] [--threads N]
//                                  [--evaluations N] [--identify greedy|thermal-node]
//                                  [--training cycle|two-runs]
//                                  [--folds-by time|runs] [--sensor drawn|coil]
//                                  [--without turn-on,self-heating]
//                                  [--oracle-without NAME,...] [--oracle-target gyro|drift]
//                                  [--oracle-states true|measured] [--oracle-lookahead S]
//                                  [--oracle-constants law|cv|cv-pooled|fit] [--gyro-delay S]
//                                  [--rate-span S] [--node-channel own|any]
//                                  [--max-cancellation X] [--node-under-dynamics on|off]
//                                  [--cv-score geometric|pooled] [--min-gain X] [--search-folds N] [--training-noise K]
//                                  [--bag B] [--training-quiet bias|gyro|all] [--chamber-air NOISE:RESOLUTION]
//                                  [--log-start power-on|running|estimated] [--json FILE]
//
// Per law seed s: the unit sim::draw_unit(s) runs a two-cycle `cycle` programme; cycle 1
// is the training log, cycle 2 the "next cycle". Two other profiles of two distinct
// kinds drawn from {slow, fast, staircase, partial, wander} by the seed are new runs of
// the same unit (powered on anew, their own noise). Each method is calibrated once per
// law, as `thermodrift fit` would calibrate it, and evaluated on each test log with
// 1800 s of settling; the ratio is the held-out MSE over the simulator's true noise floor
// of that log from 1800 s on (a perfect model scores 1). --training two-runs adds to
// cycle 1 a second training run of a third kind of programme (neither test kind), as a
// user with two chamber runs would fit them (--data twice). The `oracle` row is a bound, not
// a method: least squares on the law's own regressors and true states (sim::law_regressors),
// so only the coefficients come from the training log. --sensor coil (a diagnostic) puts
// every thermometer on its own coil; --without leaves the turn-on transient or the
// self-heating out of every unit; --oracle-without NAME,... leaves regressors out of the
// oracle. --training-noise K (K > 0) trains on cycle 1 of the same unit and programme with
// another noise realization (the tests keep theirs): how much a law's figures move when
// its training data are drawn again. --bag B (a diagnostic) fits B models on B noise draws
// (K, K+1, ...) and judges the average of their predictions: what the training noise costs,
// as if the user had B recordings of the same programme (fit times are the first model's).
// --oracle-target drift fits and judges the oracle on the noise-free drift (with
// --oracle-without: how far one law's aliases are from it); --training-quiet bias|gyro|all
// trains on the cycle simulated again without the bias instability or any noise. The JSON
// gives every test's `distance`, the MSE against the smoothed true drift over the floor,
// and every axis' `training_distance`, the same on the training rows. --oracle-states
// measured rebuilds the oracle's states from the thermometers; --oracle-constants chooses
// its constants from the training log (choose_constants).
// docs/generalization.md says what the methods are and
// has measured figures.
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "generalization_summary.hpp"
#include "thermodrift/features/moving_average.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/sim/law_family.hpp"
#include "thermodrift/sim/standard_normal.hpp"
#include "thermodrift/tune/calibration.hpp"

using namespace thermodrift;
using namespace thermodrift::bench;

namespace {

constexpr double smoothing_s = 100;  // the paper's window: the floor is of data smoothed so
constexpr double settle_s = 1800;    // lags start in equilibrium; the first 30 min are not judged

std::atomic<bool> interrupted{false};  // the one thing a signal handler may touch
extern "C" void on_interrupt(int signal_number) {
  if (interrupted.load()) std::_Exit(128 + signal_number);
  interrupted.store(true);
}

// CPU seconds of the calling thread: each law runs on one thread (tuning threads = 1), so
// this is the fit's cost whatever the neighbours on a shared machine are doing.
double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

struct Stopwatch {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  double cpu = thread_cpu_seconds();
  Cost elapsed() const {
    return {thread_cpu_seconds() - cpu,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count()};
  }
};

// What the constants are chosen by: the searches' score (the geometric mean of the blocks'
// MSEs), the pooled blocked-CV MSE, or the in-sample fit (a prediction-error fit).
enum class ConstantsScore { typical_block, pooled, in_sample };

struct Arguments {
  std::string seed_list = "acceptance";
  std::vector<std::uint64_t> seeds;
  std::size_t limit = 0;  // 0: every seed
  std::vector<Method> methods{Method::paper, Method::linear, Method::stepwise, Method::svr};
  int threads = 2;
  long evaluations = SvrTuningOptions{}.evaluations;
  std::string json;
  FeatureSelectionOptions::Method identify = FeatureSelectionOptions{}.method;  // --features auto's search
  bool two_runs = false;                        // --training two-runs
  FoldsBy folds_by = CalibrationOptions{}.folds_by;
  // A diagnostic, not a test: each axis' sensor moved onto its own coil (2 s), so the
  // temperature column is the coil's and no thermal path lies between them.
  bool sensor_on_coil = false;
  // Diagnostics too: physics left out of every drawn unit (--without turn-on,self-heating).
  bool without_turn_on = false;
  bool without_self_heating = false;
  std::vector<std::size_t> oracle_without;  // regressors the oracle leaves out (sim::law_regressor_names)
  bool oracle_on_drift = false;  // --oracle-target drift: the oracle fits and is judged on the true drift
  // --oracle-states measured: the oracle's states rebuilt from the thermometers by a Kalman
  // filter on the law's own network (sim::law_regressors_from_thermometers), not the true ones.
  bool oracle_measured = false;
  // --oracle-lookahead S (with measured states): each row's states from the thermometers up
  // to S seconds later (inf: the whole run), where the filter reads only those up to the row.
  double oracle_lookahead = 0;
  // --oracle-constants law|cv|cv-pooled|fit: the law's own constants, or each axis' chosen
  // from the training log, starting at the law's (choose_constants).
  bool oracle_cv_constants = false;
  ConstantsScore oracle_constants_score = ConstantsScore::typical_block;
  // --gyro-delay S (a diagnostic): every log's gyro (and true drift) delayed by S seconds, so a
  // model predicts the drift S seconds back from the thermometers up to now: what a
  // compensation of recorded files could gain by looking S seconds ahead.
  double gyro_delay = 0;
  std::optional<double> rate_span;          // --rate-span of the --features auto methods (fit's default if absent)
  bool other_channels = FeatureSelectionOptions{}.other_channels;  // --node-channel any|own
  double max_cancellation = FeatureSelectionOptions{}.max_cancellation;  // --max-cancellation (thermal node)
  bool node_under_dynamics = FeatureSelectionOptions{}.node_under_dynamics;  // --node-under-dynamics on|off
  FeatureSelectionOptions::CvScore cv_score = FeatureSelectionOptions{}.cv_score;  // --cv-score geometric|pooled
  double min_gain = FeatureSelectionOptions{}.min_gain;  // --min-gain: the searches' penalty per term (the kernel check takes it too)
  int search_folds = FeatureSelectionOptions{}.folds;  // --search-folds N: the searches' blocked CV
  std::uint64_t training_noise = 0;  // --training-noise K: 0 the training run's own noise, K > 0 another draw
  std::size_t bag = 1;  // --bag B: B models on B noise draws of the training cycle, their predictions averaged
  // --training-quiet bias|gyro|all (a diagnostic): the training cycle simulated again without
  // the bias instability, without the gyro's noise, or without any noise (the thermometers'
  // too); the tests keep theirs: what the noise costs.
  std::string training_quiet;
  // --chamber-air NOISE:RESOLUTION: the chamber's air temperature as a fourth thermometer,
  // as a chamber log has it (white noise of NOISE °C, quantized to RESOLUTION °C): a channel
  // upstream of every node, for the node search and the measured gradients.
  std::optional<std::pair<double, double>> chamber_air;
  // --log-start: where evaluate starts each test log but the carried one (evaluate's default)
  LogStart log_start = LogStart::estimated;
};

std::vector<std::string> split(const std::string& list) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (begin <= list.size()) {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    parts.push_back(list.substr(begin, end - begin));
    begin = end + 1;
  }
  return parts;
}

Arguments parse(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) {
      fmt::print(stderr,
                 "usage: {} [--seeds acceptance|development|S,S,...] [--limit N] "
                 "[--methods paper,linear,stepwise,svr,oracle] [--threads N] [--evaluations N] "
                 "[--identify greedy|thermal-node] [--training cycle|two-runs] [--folds-by time|runs] "
                 "[--sensor drawn|coil] [--without turn-on,self-heating] [--oracle-without NAME,...] "
                 "[--oracle-target gyro|drift] [--oracle-states true|measured] [--oracle-lookahead S] [--oracle-constants law|cv|cv-pooled|fit] [--gyro-delay S] [--rate-span S] [--node-channel own|any] [--max-cancellation X] [--node-under-dynamics on|off] "
                 "[--cv-score geometric|pooled] [--min-gain X] [--search-folds N] [--training-noise K] [--bag B] [--training-quiet bias|gyro|all] [--chamber-air NOISE:RESOLUTION] [--log-start power-on|running|estimated] [--json FILE]\n",
                 argv[0]);
      std::exit(2);
    }
    const std::string value = argv[++i];
    if (flag == "--seeds") args.seed_list = value;
    else if (flag == "--limit") args.limit = std::stoul(value);
    else if (flag == "--threads") args.threads = std::max(1, std::stoi(value));
    else if (flag == "--evaluations") args.evaluations = std::stol(value);
    else if (flag == "--json") args.json = value;
    else if (flag == "--rate-span") args.rate_span = std::stod(value);
    else if (flag == "--max-cancellation") args.max_cancellation = std::stod(value);
    else if (flag == "--min-gain") args.min_gain = std::stod(value);
    else if (flag == "--training-noise") args.training_noise = std::stoull(value);
    else if (flag == "--training-quiet" && (value == "bias" || value == "gyro" || value == "all")) {
      args.training_quiet = value;
    }
    else if (flag == "--log-start") args.log_start = parse_log_start(value);
    else if (flag == "--chamber-air") {
      const auto colon = value.find(':');
      if (colon == std::string::npos) throw std::invalid_argument("--chamber-air NOISE:RESOLUTION");
      args.chamber_air = std::pair{std::stod(value.substr(0, colon)), std::stod(value.substr(colon + 1))};
    }
    else if (flag == "--search-folds") args.search_folds = std::max(2, std::stoi(value));
    else if (flag == "--bag") args.bag = std::max<std::size_t>(1, std::stoul(value));
    else if (flag == "--node-under-dynamics" && (value == "on" || value == "off")) args.node_under_dynamics = value == "on";
    else if (flag == "--cv-score" && (value == "geometric" || value == "pooled")) {
      args.cv_score = value == "pooled" ? FeatureSelectionOptions::CvScore::pooled : FeatureSelectionOptions::CvScore::geometric;
    }
    else if (flag == "--node-channel" && (value == "own" || value == "any")) args.other_channels = value == "any";
    else if (flag == "--identify" && (value == "greedy" || value == "thermal-node")) {
      args.identify = value == "greedy" ? FeatureSelectionOptions::Method::greedy
                                        : FeatureSelectionOptions::Method::thermal_node;
    }
    else if (flag == "--training" && (value == "cycle" || value == "two-runs")) args.two_runs = value == "two-runs";
    else if (flag == "--folds-by") args.folds_by = parse_folds_by(value);
    else if (flag == "--sensor" && (value == "drawn" || value == "coil")) args.sensor_on_coil = value == "coil";
    else if (flag == "--without") {
      for (const auto& name : split(value)) {
        if (name == "turn-on") args.without_turn_on = true;
        else if (name == "self-heating") args.without_self_heating = true;
        else throw std::invalid_argument(fmt::format("unknown physics '{}' (turn-on, self-heating)", name));
      }
    }
    else if (flag == "--oracle-target" && (value == "gyro" || value == "drift")) args.oracle_on_drift = value == "drift";
    else if (flag == "--oracle-states" && (value == "true" || value == "measured")) args.oracle_measured = value == "measured";
    else if (flag == "--oracle-lookahead") args.oracle_lookahead = std::stod(value);
    else if (flag == "--oracle-constants" && (value == "law" || value == "cv" || value == "cv-pooled" || value == "fit")) {
      args.oracle_cv_constants = value != "law";
      args.oracle_constants_score = value == "cv"          ? ConstantsScore::typical_block
                                    : value == "cv-pooled" ? ConstantsScore::pooled
                                                           : ConstantsScore::in_sample;
    }
    else if (flag == "--gyro-delay") args.gyro_delay = std::stod(value);
    else if (flag == "--oracle-without") {
      const auto names = sim::law_regressor_names();
      for (const auto& name : split(value)) {
        const auto found = std::find(names.begin(), names.end(), name);
        if (found == names.end()) throw std::invalid_argument(fmt::format("unknown regressor '{}'", name));
        args.oracle_without.push_back(static_cast<std::size_t>(found - names.begin()));
      }
    }
    else if (flag == "--methods") {
      args.methods.clear();
      for (const auto& name : split(value)) args.methods.push_back(parse_method(name));
    } else {
      fmt::print(stderr, "unknown option {}\n", flag);
      std::exit(2);
    }
  }
  if (args.oracle_measured && args.oracle_cv_constants) {
    throw std::invalid_argument("--oracle-constants reads the true states; not with --oracle-states measured");
  }
  if (args.seed_list == "acceptance") args.seeds = sim::acceptance_law_seeds();
  else if (args.seed_list == "development") args.seeds = sim::development_law_seeds();
  else for (const auto& seed : split(args.seed_list)) args.seeds.push_back(std::stoull(seed));
  if (args.limit > 0 && args.limit < args.seeds.size()) args.seeds.resize(args.limit);
  return args;
}

// Rows [begin, end) of a run, as a run of its own (time still counted from power-on).
sim::ChamberRun slice(const sim::ChamberRun& run, std::size_t begin, std::size_t end) {
  sim::ChamberRun part;
  part.column_names = run.column_names;
  part.rate_hz = run.rate_hz;
  for (const auto& column : run.columns) {
    part.columns.emplace_back(column.begin() + static_cast<std::ptrdiff_t>(begin),
                              column.begin() + static_cast<std::ptrdiff_t>(end));
  }
  part.cycle_start_s = {run.column("time_s")[begin]};
  return part;
}

// A log to judge a model on, with the true floor over the rows it is judged on.
struct TestLog {
  std::string name;  // "next cycle", the programme's kind, or carried_test
  ChamberLog log;
  std::array<double, 3> floor{};
  sim::ChamberRun run;             // the rows of `log`, with the true drift (for the oracle)
  sim::LawRegressors regressors;   // the law's regressors on those rows (oracle only)
  // Set: judged from this row of `log` on, every filter and lag carried from its first row
  // (evaluate_from) instead of starting in equilibrium and settling.
  std::optional<std::size_t> carried_from_row;
};

constexpr const char* kMeasuredAir = "temp_chamber_measured";

// The unit through a programme; with --chamber-air, the run also holds the chamber air as
// its sensor reads it (its noise drawn from the run's own noise seed).
sim::ChamberRun simulate(const sim::UnitLaw& unit, const sim::Setpoint& programme, std::uint64_t noise_seed,
                         const std::optional<std::pair<double, double>>& chamber_air, double gyro_delay_s = 0) {
  sim::ChamberRun run = sim::simulate_unit(unit, programme, noise_seed);
  if (gyro_delay_s > 0) {  // the first rows repeat the first reading
    const auto delay = static_cast<std::size_t>(std::llround(gyro_delay_s * run.rate_hz));
    for (const auto& names : {sim::gyro_columns, sim::drift_columns}) {
      for (const std::string_view name : names) {
        auto& column = run.columns[static_cast<std::size_t>(
            std::find(run.column_names.begin(), run.column_names.end(), name) - run.column_names.begin())];
        for (std::size_t k = column.size(); k-- > 0;) column[k] = column[k >= delay ? k - delay : 0];
      }
    }
  }
  if (chamber_air) {
    sim::StandardNormal normal(sim::derive_seed(noise_seed, 0xa1));
    std::vector<double> measured = run.column("temp_chamber");
    for (double& value : measured) {
      value += chamber_air->first * normal();
      if (chamber_air->second > 0) value = chamber_air->second * std::round(value / chamber_air->second);
    }
    run.column_names.emplace_back(kMeasuredAir);
    run.columns.push_back(std::move(measured));
  }
  return run;
}

// The log a model is fitted on or judged on: the axes' thermometers, and the measured
// chamber air as a fourth channel when the run has it.
ChamberLog log_of(const sim::ChamberRun& run) {
  ChamberLog log = sim::to_chamber_log(run);
  const auto air = std::find(run.column_names.begin(), run.column_names.end(), kMeasuredAir);
  if (air != run.column_names.end()) {
    log.temperature_names.emplace_back(kMeasuredAir);
    log.temperature.push_back(run.columns[static_cast<std::size_t>(air - run.column_names.begin())]);
  }
  return log;
}

TestLog make_test(std::string name, const sim::ChamberRun& run) {
  const auto first_row = static_cast<std::size_t>(std::llround(settle_s * run.rate_hz));
  return {std::move(name), log_of(run), run.noise_floor(smoothing_s, first_row), run, {}};
}

// Rows [begin, end) of every regressor.
sim::LawRegressors slice(const sim::LawRegressors& regressors, std::size_t begin, std::size_t end) {
  sim::LawRegressors part;
  for (std::size_t a = 0; a < 3; ++a) {
    for (const auto& column : regressors[a]) {
      part[a].emplace_back(column.begin() + static_cast<std::ptrdiff_t>(begin),
                           column.begin() + static_cast<std::ptrdiff_t>(end));
    }
  }
  return part;
}

// The 100 s trailing mean of a column at 1 Hz, from the first full window on (row
// window - 1 of the input is row 0 of the output): what the pipeline smooths.
std::vector<double> smoothed(const std::vector<double>& column, double rate_hz) {
  TrailingMean mean(smoothing_s);
  std::vector<double> out;
  const auto window = static_cast<std::size_t>(std::llround(smoothing_s * rate_hz));
  for (std::size_t k = 0; k < column.size(); ++k) {
    const double value = mean.push(static_cast<double>(k) / rate_hz, column[k]);
    if (k + 1 >= window) out.push_back(value);
  }
  return out;
}

// One axis of a run as the oracle sees it: smoothed regressors (columns) and gyro (or, with
// `on_drift`, the true drift without its noise).
struct OracleRows {
  Eigen::MatrixXd x;
  Eigen::VectorXd y;
};

OracleRows oracle_rows(const sim::ChamberRun& run, const sim::LawRegressors& regressors, std::size_t axis,
                       bool on_drift) {
  const std::vector<double> y =
      smoothed(run.column(on_drift ? sim::drift_columns[axis] : sim::gyro_columns[axis]), run.rate_hz);
  OracleRows rows{Eigen::MatrixXd(static_cast<Eigen::Index>(y.size()), sim::kLawRegressors),
                  Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()))};
  for (std::size_t j = 0; j < sim::kLawRegressors; ++j) {
    const std::vector<double> column = smoothed(regressors[axis][j], run.rate_hz);
    rows.x.col(static_cast<Eigen::Index>(j)) = Eigen::Map<const Eigen::VectorXd>(column.data(), rows.y.size());
  }
  return rows;
}

// The rows of several logs one after the other, every `every`-th of each log.
OracleRows stacked(const std::vector<OracleRows>& parts, Eigen::Index every = 1) {
  Eigen::Index n = 0;
  for (const auto& part : parts) n += (part.y.size() + every - 1) / every;
  OracleRows all{Eigen::MatrixXd(n, static_cast<Eigen::Index>(sim::kLawRegressors)), Eigen::VectorXd(n)};
  Eigen::Index row = 0;
  for (const auto& part : parts) {
    for (Eigen::Index k = 0; k < part.y.size(); k += every, ++row) {
      all.x.row(row) = part.x.row(k);
      all.y[row] = part.y[k];
    }
  }
  return all;
}

// The programme up to `seconds` (its knots to the first at or past seconds + 1 s): the same
// air up to there, so a unit run through it gives the same rows, without the rest.
sim::Setpoint programme_prefix(const sim::Setpoint& programme, double seconds) {
  sim::Setpoint prefix = programme;
  std::size_t knots = 0;
  while (knots < programme.time_s.size() && (knots == 0 || programme.time_s[knots - 1] < seconds + 1)) ++knots;
  prefix.time_s.resize(knots);
  prefix.temperature_c.resize(knots);
  return prefix;
}

// Least squares on scaled columns; a regressor the law does not have is a column of zeros,
// which the rank-revealing QR leaves at zero.
Eigen::VectorXd oracle_least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  Eigen::VectorXd scale = x.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < scale.size(); ++j) {
    if (scale[j] == 0) scale[j] = 1;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x * scale.cwiseInverse().asDiagonal());
  qr.setThreshold(1e-12);
  return scale.cwiseInverse().asDiagonal() * Eigen::VectorXd(qr.solve(y));
}

// --oracle-constants cv|cv-pooled|fit: the law's forms with its constants chosen by the data. Each axis'
// thermal and hysteresis constants (the case's and the chain's time constants, the tanh
// step's centre and width, the radial gradient's lag, the memory's time constant and rate
// scale, the play's width, the turn-on's time constant; not the back coupling or the
// self-heating) move, from the law's own values, by a coordinate pattern search (steps of
// 2^±1/2, 2^±1/4, 2^±1/8; the step's centre ±4, 2, 1 °C; time constants up to a quarter of
// the training log's span, widths and rate scales within broad bounds) while the
// least-squares fit's blocked 10-fold CV on the training cycle falls, scored as the searches
// score (the geometric mean of the blocks' MSEs; every 10th smoothed row; `cv-pooled`: their
// pooled MSE; `fit`: the in-sample MSE, a prediction-error fit). The states are the true
// ones of the moved unit, driven by the chamber air; with two training logs, their rows
// follow each other in the CV's blocks. Started at the truth, the search finds the score's
// local minimum nearest it: what choosing the constants from one noisy cycle costs a method
// that knows every form, at best (docs/generalization.md, "What choosing the constants costs").
struct ChosenConstants {
  sim::UnitLaw unit;          // the law with axis `axis`'s constants (and the case's) moved
  std::vector<std::string> moves;  // "name:law->chosen" for each constant that moved
};

ChosenConstants choose_constants(const sim::UnitLaw& law,
                                       const std::vector<std::pair<const sim::Setpoint*, const sim::ChamberRun*>>& logs,
                                       std::size_t axis, ConstantsScore by) {
  struct Constant {
    std::string name;
    double* value;
    bool additive;  // °C steps (the step's centre), else steps in log2
    double low = 0, high = std::numeric_limits<double>::infinity();  // log steps stay within [low, high]
  };
  ChosenConstants chosen{law, {}};
  sim::AxisLaw& a = chosen.unit.axes[axis];
  // Time constants up to a quarter of the first log's span, as the searches allow.
  const double longest = 0.25 * static_cast<double>(logs.front().second->rows()) / logs.front().second->rate_hz;
  std::vector<Constant> constants{{"case_s", &chosen.unit.case_time_constant_s, false, 2, longest}};
  for (std::size_t k = 0; k < a.node_time_constants_s.size(); ++k) {
    constants.push_back({fmt::format("node{}_s", k), &a.node_time_constants_s[k], false, 2, longest});
  }
  if (a.shape == sim::StaticShape::tanh_step && a.step_dph != 0) {
    constants.push_back({"step_centre_c", &a.step_centre_c, true});
    constants.push_back({"step_width_c", &a.step_width_c, false, 0.5, 200});
  }
  if (a.radial_gradient_rate_dph != 0) constants.push_back({"radial_s", &a.radial_time_constant_s, false, 2, longest});
  if (a.hysteresis == sim::HysteresisKind::memory) {
    constants.push_back({"memory_s", &a.hysteresis_time_constant_s, false, 2, longest});
    constants.push_back({"memory_r0", &a.hysteresis_rate_scale, false, 0.01, 2});
  }
  if (a.hysteresis == sim::HysteresisKind::play) constants.push_back({"play_w", &a.hysteresis_width_c, false, 0.05, 20});
  if (a.turn_on_dph != 0) constants.push_back({"turn_on_s", &a.turn_on_time_constant_s, false, 2, longest});
  std::vector<double> original;
  for (const auto& c : constants) original.push_back(*c.value);

  // Each log's rows are a prefix of its programme's: only that much is simulated.
  std::vector<sim::Setpoint> programmes;
  for (const auto& [programme, run] : logs) {
    programmes.push_back(programme_prefix(*programme, static_cast<double>(run->rows()) / run->rate_hz));
  }
  const auto score = [&] {
    std::vector<OracleRows> parts;
    for (std::size_t i = 0; i < logs.size(); ++i) {
      const sim::ChamberRun& run = *logs[i].second;
      parts.push_back(oracle_rows(run, slice(sim::law_regressors(chosen.unit, programmes[i]), 0, run.rows()), axis, false));
    }
    const auto [x, y] = stacked(parts, 10);
    if (by == ConstantsScore::in_sample) return (y - x * oracle_least_squares(x, y)).squaredNorm();
    double log_sum = 0, sum = 0;
    const auto blocks = blocked_folds(y.size(), 10);
    for (const SampleRange& block : blocks) {
      const Eigen::VectorXd beta = oracle_least_squares(rows_except(x, block), rows_except(y, block));
      const Eigen::Index begin = block.begin, size = block.end - block.begin;
      const double squares = (y.segment(begin, size) - x.middleRows(begin, size) * beta).squaredNorm();
      log_sum += std::log(squares / static_cast<double>(size));
      sum += squares;
    }
    return by == ConstantsScore::pooled ? sum : std::exp(log_sum / static_cast<double>(blocks.size()));
  };
  double best = score();
  for (const double step : {0.5, 0.25, 0.125}) {
    bool moved = true;
    while (moved && !interrupted.load()) {
      moved = false;
      for (const auto& c : constants) {
        for (const double sign : {1.0, -1.0}) {
          for (;;) {
            const double before = *c.value;
            *c.value = c.additive ? before + sign * 8 * step : before * std::exp2(sign * step);
            if (!c.additive && (*c.value < std::min(c.low, before) || *c.value > std::max(c.high, before))) {
              *c.value = before;
              break;
            }
            const double trial = score();
            if (trial < best) {
              best = trial;
              moved = true;
            } else {
              *c.value = before;
              break;
            }
          }
        }
      }
    }
  }
  for (std::size_t k = 0; k < constants.size(); ++k) {
    if (*constants[k].value != original[k]) {
      chosen.moves.push_back(fmt::format("{}:{:.4g}->{:.4g}", constants[k].name, original[k], *constants[k].value));
    }
  }
  return chosen;
}

// The law's own structure on its true states, fitted by least squares on the training rows:
// no identification error at all, only the coefficients left to one training log. What it
// leaves held out is what the training log cannot tell apart (near-collinear terms under
// its one ramp rate) plus the noise, so it bounds what any method could reach from that log.
// `without`: regressors left out (--oracle-without), to see which physics a method must capture.
// `on_drift` (--oracle-target drift): fitted on the smoothed true drift and judged against it,
// noise-free. With `without`, that measures aliases: the law B the remaining regressors make
// of law A on A's training log. The in-sample ratio is then how far apart the two units'
// training logs are (in floors, before noise), a test's ratio how far apart their drift is
// there. Where the first is within what the noise hides and the second is large, no method
// trained on that log can be near the floor on both units.
MethodResult fit_oracle(const std::vector<std::pair<const sim::ChamberRun*, const sim::LawRegressors*>>& training,
                        const std::array<double, 3>& training_floor, const std::vector<TestLog>& tests,
                        const std::vector<std::size_t>& without, bool on_drift) {
  MethodResult result;
  result.method = Method::oracle;
  const Stopwatch clock;
  result.tests.resize(tests.size());
  for (std::size_t a = 0; a < 3; ++a) {
    std::vector<OracleRows> parts;
    for (const auto& [run, regressors] : training) parts.push_back(oracle_rows(*run, *regressors, a, on_drift));
    auto [x, y] = stacked(parts);
    const Eigen::Index n = y.size();
    for (const std::size_t j : without) x.col(static_cast<Eigen::Index>(j)).setZero();
    const Eigen::VectorXd beta = oracle_least_squares(x, y);
    result.in_sample[a] = (y - x * beta).squaredNorm() / static_cast<double>(n) / training_floor[a];
    // The same fit against the noise-free drift of the training rows (the same rows as y
    // when on_drift).
    double distance_sum = 0;
    for (std::size_t k = 0; k < training.size(); ++k) {
      const OracleRows truth = on_drift ? parts[k] : oracle_rows(*training[k].first, *training[k].second, a, true);
      distance_sum += (truth.y - truth.x * beta).squaredNorm();
    }
    result.training_distance[a] = distance_sum / static_cast<double>(n) / training_floor[a];
    for (std::size_t j = 0; j < sim::kLawRegressors; ++j) {
      if (beta[static_cast<Eigen::Index>(j)] != 0) result.terms[a].emplace_back(sim::law_regressor_names()[j]);
    }
    for (std::size_t t = 0; t < tests.size(); ++t) {
      const OracleRows judged = oracle_rows(tests[t].run, tests[t].regressors, a, on_drift);
      // Judged from settle_s on, as the models are (the carried test: from its own row).
      const std::size_t window = static_cast<std::size_t>(std::llround(smoothing_s * tests[t].run.rate_hz));
      const std::size_t first_input_row =
          tests[t].carried_from_row ? *tests[t].carried_from_row
                                    : static_cast<std::size_t>(std::llround(settle_s * tests[t].run.rate_hz));
      const auto first = static_cast<Eigen::Index>(first_input_row - (window - 1));
      const Eigen::VectorXd residual = (judged.y - judged.x * beta).tail(judged.y.size() - first);
      const OracleRows truth = on_drift ? judged : oracle_rows(tests[t].run, tests[t].regressors, a, true);
      result.tests[t].distance[a] =
          (truth.y - truth.x * beta).tail(truth.y.size() - first).squaredNorm() /
          static_cast<double>(truth.y.size() - first) / tests[t].floor[a];
      result.tests[t].mse[a] = residual.squaredNorm() / static_cast<double>(residual.size());
      result.tests[t].floor[a] = tests[t].floor[a];
      result.tests[t].ratio[a] = result.tests[t].mse[a] / tests[t].floor[a];
    }
  }
  result.fit = clock.elapsed();
  return result;
}

// Two distinct kinds of programme, drawn from the law's seed (the engine's raw output, which
// is the same with every standard library). Over the 40 development seeds each kind is
// drawn 11-22 times in all, though seeds 1-4 all draw partial first.
constexpr std::array<sim::ProfileKind, 5> other_kinds = {sim::ProfileKind::slow, sim::ProfileKind::fast,
                                                         sim::ProfileKind::staircase, sim::ProfileKind::partial,
                                                         sim::ProfileKind::wander};

std::array<sim::ProfileKind, 2> other_profiles(std::uint64_t law_seed) {
  std::mt19937_64 engine(sim::derive_seed(law_seed, 0x0b1));
  const std::uint64_t first = engine() % other_kinds.size();
  const std::uint64_t second = (first + 1 + engine() % (other_kinds.size() - 1)) % other_kinds.size();
  return {other_kinds[first], other_kinds[second]};
}

// --training two-runs: the second training run's kind, one of the three the tests do not use.
sim::ProfileKind second_training_profile(std::uint64_t law_seed) {
  const auto tested = other_profiles(law_seed);
  std::vector<sim::ProfileKind> left;
  for (sim::ProfileKind kind : other_kinds) {
    if (kind != tested[0] && kind != tested[1]) left.push_back(kind);
  }
  std::mt19937_64 engine(sim::derive_seed(law_seed, 0x0b2));
  return left[engine() % left.size()];
}

// The rows of a test an axis is judged on (as evaluate and evaluate_from judge them), with
// the smoothed gyro and the model's prediction there.
struct JudgedRows {
  std::vector<std::size_t> row;
  Eigen::VectorXd target, predicted;
};
// With `evaluated` (evaluate_axes' result for this axis), its prediction of the same rows,
// from the log start it was asked for, in place of the model's from power-on.
JudgedRows judge_axis(const DriftModel& model, const TestLog& test, std::size_t axis, double settle = settle_s,
                      const AxisEvaluation* evaluated = nullptr) {
  const auto& axis_model = model.axes[axis];
  const auto channel = temperature_channel_per_axis(test.log).at(axis);
  const FeatureTable table = build_feature_table(axis_model.pipeline, test.log, axis, channel, false);
  std::vector<Eigen::Index> kept;
  JudgedRows judged;
  for (std::size_t i = 0; i < table.rows(); ++i) {
    const bool settled =
        test.carried_from_row ? table.row[i] >= *test.carried_from_row : table.since_start[i] >= settle;
    if (!settled) continue;
    kept.push_back(static_cast<Eigen::Index>(i));
    judged.row.push_back(table.row[i]);
  }
  judged.target = table.target(kept);
  if (evaluated == nullptr) {
    judged.predicted = axis_model.predict(table.features(kept, Eigen::all));
  } else {
    if (evaluated->rows != judged.row) throw std::runtime_error("evaluate judged other rows than the bench");
    judged.predicted = Eigen::Map<const Eigen::VectorXd>(evaluated->predicted.data(),
                                                         static_cast<Eigen::Index>(evaluated->predicted.size()));
  }
  return judged;
}

// MSE of the judged rows' prediction against the unit's smoothed true drift (no noise).
double drift_mse(const JudgedRows& judged, const sim::ChamberRun& run, std::size_t axis) {
  const std::vector<double> drift = smoothed(run.column(sim::drift_columns[axis]), run.rate_hz);
  const auto window = static_cast<std::size_t>(std::llround(smoothing_s * run.rate_hz));
  double sum = 0;
  for (std::size_t i = 0; i < judged.row.size(); ++i) {
    const double error = judged.predicted[static_cast<Eigen::Index>(i)] - drift.at(judged.row[i] - (window - 1));
    sum += error * error;
  }
  return sum / static_cast<double>(judged.row.size());
}

// --training-quiet: the unit without the bias instability ("bias"), without any of the
// gyro's noise ("gyro"), or without the thermometers' noise too ("all").
sim::UnitLaw quiet_unit(sim::UnitLaw unit, const std::string& quiet) {
  unit.noise.bias_instability = 0;
  if (quiet != "bias") {
    unit.noise.angle_random_walk = 1e-9;  // a floor above zero for the in-sample ratio
    unit.noise.quantization_arcsec = 0;
  }
  if (quiet == "all") {
    unit.noise.temperature_noise_c = 0;
    unit.noise.temperature_resolution_c = 0;
  }
  return unit;
}

// What `thermodrift fit --model M [--features auto]` asks of calibrate (apps/thermodrift/fit.cpp
// with its defaults: C 100, σ 1, ε 0.01, tolerance 1e-3; AFSA, blocked 5-fold CV, seed 1),
// with one tuning thread so that a law's cost is one thread's.
CalibrationOptions fit_options(Method method, long evaluations) {
  CalibrationOptions options;
  options.model = model_kind(method);
  options.terms = method == Method::paper ? std::vector<std::string>{"dT", "rate"} : std::vector<std::string>{"auto"};
  if (options.model == ModelKind::svr) {
    options.svr.C = 100.0;
    options.svr.gamma = gamma_of_sigma(1.0);
    options.svr.epsilon = 0.01;
    options.svr.tolerance = 1e-3;
    SvrTuningOptions tuning;
    tuning.seed = 1;
    tuning.threads = 1;
    tuning.evaluations = evaluations;
    tuning.epsilon = options.svr.epsilon;
    tuning.solver = options.svr;
    options.tuning = tuning;
  }
  // Stops the final fits' tuning on Ctrl-C (judge_by_svr's short searches take no callback:
  // they run to their end, a few seconds; a second Ctrl-C ends the process at once).
  options.tuning_progress = [](std::size_t, const optim::Progress&) { return !interrupted.load(); };
  return options;
}

LawResult run_law(std::uint64_t seed, const Arguments& args) {
  const Stopwatch law_clock;
  LawResult law;
  law.seed = seed;
  sim::UnitLaw unit = sim::draw_unit(seed);
  if (args.sensor_on_coil) {
    for (std::size_t a = 0; a < 3; ++a) {
      unit.axes[a].sensor_axis = static_cast<int>(a);
      unit.axes[a].sensor_node = static_cast<int>(unit.axes[a].node_time_constants_s.size()) - 1;
      unit.axes[a].sensor_time_constant_s = 2;
    }
  }
  if (args.without_self_heating) unit.case_self_heating_c = 0;
  for (auto& axis : unit.axes) {
    if (args.without_turn_on) axis.turn_on_dph = 0;
    if (args.without_self_heating) axis.self_heating_c = 0;
  }
  const bool oracle = std::find(args.methods.begin(), args.methods.end(), Method::oracle) != args.methods.end();
  const sim::Setpoint training_programme = sim::draw_profile(sim::ProfileKind::cycle, unit, seed, 2);
  const sim::ChamberRun training_run = simulate(unit, training_programme, sim::derive_seed(seed, 1), args.chamber_air, args.gyro_delay);
  const std::size_t second_cycle = training_run.cycle_start_rows().at(1);
  // The oracle's states: the true ones, or (--oracle-states measured) rebuilt from each run's
  // thermometers, the air's rate intensity chosen by the likelihood of the training cycle's.
  double air_rate_intensity = 0;
  if (oracle && args.oracle_measured) {
    const sim::ChamberRun cycle = slice(training_run, 0, second_cycle);
    double best = -std::numeric_limits<double>::infinity();
    for (double intensity = 1e-12; intensity < 2e-6; intensity *= 10) {
      const double likelihood = sim::law_regressors_from_thermometers(unit, cycle, intensity).log_likelihood;
      if (likelihood > best) {
        best = likelihood;
        air_rate_intensity = intensity;
      }
    }
    law.air_rate_intensity = air_rate_intensity;
  }
  // --training-noise K: cycle 1 of the same programme with another noise draw (ARW, bias
  // instability, thermometer noise); the next cycle is still judged on the run above.
  const auto training_draw = [&](std::uint64_t draw) {
    if (draw == 0 && args.training_quiet.empty()) return slice(training_run, 0, second_cycle);
    const sim::UnitLaw& drawn = args.training_quiet.empty() ? unit : quiet_unit(unit, args.training_quiet);
    return slice(simulate(drawn, training_programme, sim::derive_seed(sim::derive_seed(seed, 1), draw), args.chamber_air, args.gyro_delay),
                 0, second_cycle);
  };
  const sim::ChamberRun first = training_draw(args.training_noise);
  const bool first_is_cycle_1 = args.training_noise == 0 && args.training_quiet.empty();
  sim::Setpoint second_programme;
  sim::ChamberRun second_run;
  if (args.two_runs) {
    second_programme = sim::draw_profile(second_training_profile(seed), unit, sim::derive_seed(seed, 14));
    second_run = simulate(unit, second_programme, sim::derive_seed(seed, 4), args.chamber_air, args.gyro_delay);
  }
  // --oracle-constants cv|cv-pooled|fit: each axis' states from its own unit, its constants
  // chosen on the training log(s).
  std::array<sim::UnitLaw, 3> oracle_units{unit, unit, unit};
  std::array<std::vector<std::string>, 3> oracle_moves;
  if (oracle && args.oracle_cv_constants) {
    std::vector<std::pair<const sim::Setpoint*, const sim::ChamberRun*>> logs{{&training_programme, &first}};
    if (args.two_runs) logs.emplace_back(&second_programme, &second_run);
    for (std::size_t a = 0; a < 3; ++a) {
      ChosenConstants chosen = choose_constants(unit, logs, a, args.oracle_constants_score);
      oracle_units[a] = std::move(chosen.unit);
      oracle_moves[a] = std::move(chosen.moves);
    }
  }
  auto regressors_of = [&](const sim::Setpoint& programme, const sim::ChamberRun& run) {
    if (!oracle) return sim::LawRegressors{};
    if (args.oracle_cv_constants) {
      sim::LawRegressors combined;
      for (std::size_t a = 0; a < 3; ++a) combined[a] = std::move(sim::law_regressors(oracle_units[a], programme)[a]);
      return combined;
    }
    if (args.oracle_measured) {
      return sim::law_regressors_from_thermometers(unit, run, air_rate_intensity, args.oracle_lookahead).regressors;
    }
    return sim::law_regressors(unit, programme);
  };
  const sim::LawRegressors training_regressors = regressors_of(training_programme, training_run);
  const sim::LawRegressors first_regressors =
      !oracle ? sim::LawRegressors{}
      : args.oracle_measured && !first_is_cycle_1 ? regressors_of(training_programme, first)
                                                  : slice(training_regressors, 0, second_cycle);
  std::vector<ChamberLog> training{log_of(first)};
  std::vector<std::pair<const sim::ChamberRun*, const sim::LawRegressors*>> oracle_training{{&first, &first_regressors}};
  sim::LawRegressors second_regressors;
  if (args.two_runs) {
    second_regressors = regressors_of(second_programme, second_run);
    training.push_back(log_of(second_run));
    oracle_training.emplace_back(&second_run, &second_regressors);
  }
  const std::array<double, 3> training_floor = first.noise_floor(smoothing_s);
  law.training_floor = training_floor;
  for (const auto& log : oracle_training) law.training_s += static_cast<double>(log.first->rows()) / log.first->rate_hz;

  std::vector<TestLog> tests;
  tests.push_back(make_test("next cycle", slice(training_run, second_cycle, training_run.rows())));
  if (oracle) tests.back().regressors = slice(training_regressors, second_cycle, training_run.rows());
  std::uint64_t stream = 2;
  for (sim::ProfileKind kind : other_profiles(seed)) {
    const sim::Setpoint programme = sim::draw_profile(kind, unit, sim::derive_seed(seed, 10 + stream));
    tests.push_back(make_test(sim::to_string(kind), simulate(unit, programme, sim::derive_seed(seed, stream), args.chamber_air, args.gyro_delay)));
    tests.back().regressors = regressors_of(programme, tests.back().run);
    ++stream;
  }
  // A diagnostic beside the tests: cycle 2 judged on the same rows with the lags carried
  // over from cycle 1, as a running compensator would. Where it is much lower than "next
  // cycle", 1800 s of settling was too short for the model's lags, not the model wrong.
  TestLog carried{carried_test, log_of(training_run), tests.front().floor, training_run,
                  training_regressors,
                  second_cycle + static_cast<std::size_t>(std::llround(settle_s * training_run.rate_hz))};
  tests.push_back(std::move(carried));
  for (const auto& test : tests) law.tests.push_back(test.name);

  // One least-squares search per axis serves the three --features auto methods, as in a report.
  std::vector<FeatureSelection> selections;
  for (Method method : args.methods) {
    if (interrupted.load()) break;
    if (method == Method::oracle) {
      law.methods.push_back(fit_oracle(oracle_training, training_floor, tests, args.oracle_without, args.oracle_on_drift));
      for (std::size_t a = 0; a < 3; ++a) {
        law.methods.back().terms[a].insert(law.methods.back().terms[a].end(), oracle_moves[a].begin(), oracle_moves[a].end());
      }
      continue;
    }
    MethodResult result;
    result.method = method;
    try {
      CalibrationOptions options = fit_options(method, args.evaluations);
      options.selection.method = args.identify;
      options.selection.other_channels = args.other_channels;
      options.selection.max_cancellation = args.max_cancellation;
      options.selection.node_under_dynamics = args.node_under_dynamics;
      options.selection.cv_score = args.cv_score;
      options.selection.min_gain = args.min_gain;
      options.selection.folds = args.search_folds;
      options.folds_by = args.folds_by;
      if (args.rate_span && method != Method::paper) options.rate_span_seconds = args.rate_span;
      if (chooses_features(options)) {
        if (selections.empty()) {
          const Stopwatch search_clock;
          selections = select_features_per_axis(training, options);
          law.search = search_clock.elapsed();
        }
        options.selections = selections;
        result.search = law.search;
      }
      const Stopwatch fit_clock;
      const Calibration calibration = calibrate(training, LogSpec{}, options);
      result.fit = fit_clock.elapsed();
      // --bag B: B - 1 more models on other noise draws of the training cycle.
      std::vector<DriftModel> bagged;
      for (std::size_t b = 1; b < args.bag && !interrupted.load(); ++b) {
        std::vector<ChamberLog> resampled = training;  // with --training two-runs, the second run too
        resampled.front() = log_of(training_draw(args.training_noise + b));
        CalibrationOptions draw_options = options;
        if (chooses_features(options)) draw_options.selections = select_features_per_axis(resampled, options);
        bagged.push_back(calibrate(resampled, LogSpec{}, draw_options).model);
      }
      const TestLog training_test = make_test("training", first);
      for (std::size_t a = 0; a < 3; ++a) {
        result.in_sample[a] = calibration.axes[a].in_sample.mse_after / training_floor[a];
        result.training_distance[a] =
            drift_mse(judge_axis(calibration.model, training_test, a, 0.0), first, a) / training_floor[a];
        result.terms[a] = calibration.model.axes[a].pipeline.term_names();
        const auto& channel = calibration.model.axes[a].pipeline.temperature_channel;
        result.temperature_channel[a] = channel ? *channel + 1 : 0;
        const auto& selection = calibration.model.axes[a].fit.feature_selection;
        if (selection) {
          for (const auto& step : selection->path) {
            if (step.action != "channel") continue;
            const std::string& text = step.term;
            std::size_t number = 0;
            double lag_cv = 0;
            const auto at = text.find("(single lag: CV MSE ");
            if (std::sscanf(text.c_str(), "temperature channel %zu", &number) == 1 && at != std::string::npos &&
                std::sscanf(text.c_str() + at, "(single lag: CV MSE %lf", &lag_cv) == 1) {
              result.channel_scores[a].push_back({static_cast<double>(number), lag_cv, step.cv_mse});
            }
          }
        }
      }
      for (const auto& test : tests) {
        std::vector<ResidualMetrics> metrics;
        // The judged rows as evaluate predicts them (from the log start it was asked for);
        // the carried test's lags run through cycle 1 instead.
        auto evaluated = [&](const DriftModel& model) {
          return test.carried_from_row ? std::vector<AxisEvaluation>{}
                                       : evaluate_axes(model, {test.log}, settle_s, {}, args.log_start);
        };
        auto judged_rows = [&](const DriftModel& model, const std::vector<AxisEvaluation>& evaluations, std::size_t a) {
          return judge_axis(model, test, a, settle_s, evaluations.empty() ? nullptr : &evaluations.at(a));
        };
        const std::vector<AxisEvaluation> evaluations = evaluated(calibration.model);
        std::vector<std::vector<AxisEvaluation>> bagged_evaluations;
        for (const auto& model : bagged) bagged_evaluations.push_back(evaluated(model));
        if (test.carried_from_row) {
          metrics = evaluate_from(calibration.model, test.log, *test.carried_from_row);
        } else {
          for (const auto& axis : evaluations) metrics.push_back(axis.metrics);
        }
        TestResult judged;
        for (std::size_t a = 0; a < 3; ++a) {
          // The judged rows' prediction, averaged over the bagged models (--bag): its MSE
          // against the gyro replaces evaluate's, its distance from the true drift is kept.
          JudgedRows mean = judged_rows(calibration.model, evaluations, a);
          for (std::size_t b = 0; b < bagged.size(); ++b) {
            const JudgedRows other = judged_rows(bagged[b], bagged_evaluations[b], a);
            if (other.row != mean.row) throw std::runtime_error("bagged models judge different rows");
            mean.predicted += other.predicted;
          }
          mean.predicted /= static_cast<double>(bagged.size() + 1);
          if (!bagged.empty()) {
            metrics[a].mse_after = (mean.target - mean.predicted).squaredNorm() / static_cast<double>(mean.row.size());
          }
          judged.distance[a] = drift_mse(mean, test.run, a) / test.floor[a];
          judged.mse[a] = metrics[a].mse_after;
          judged.floor[a] = test.floor[a];
          judged.ratio[a] = metrics[a].mse_after / test.floor[a];
        }
        result.tests.push_back(judged);
      }
    } catch (const std::exception& error) {
      result.error = error.what();
    }
    law.methods.push_back(std::move(result));
  }
  law.cost = law_clock.elapsed();
  return law;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  try {
    args = parse(argc, argv);
  } catch (const std::exception& error) {
    fmt::print(stderr, "generalization_bench: {}\n", error.what());
    return 2;
  }
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);

  fmt::print("generalization_bench: {} law(s) (--seeds {}), methods {}, AFSA budget {}, {} thread(s)\n",
             args.seeds.size(), args.seed_list, method_list(args.methods), args.evaluations, args.threads);
  fmt::print("train: cycle 1 of a two-cycle `cycle` programme{}; tests: cycle 2 (next cycle) and two other "
             "profiles (new runs of the unit); settle {:g} s; ratio = held-out MSE / true noise floor ({:g} s smoothing)\n\n",
             args.two_runs ? fmt::format(" and a run of a third kind of programme (folds by {})", to_string(args.folds_by)) : "",
             settle_s, smoothing_s);

  // Laws are independent and every seed is fixed: --threads changes the order they finish in only.
  std::vector<LawResult> laws(args.seeds.size());
  std::vector<char> finished(args.seeds.size(), 0);
  std::atomic<std::size_t> next{0};
  std::mutex mutex;  // guards laws, finished, running and stderr
  std::condition_variable changed;
  const int worker_count = std::min<int>(args.threads, static_cast<int>(args.seeds.size()));
  int running = worker_count;
  auto work = [&] {
    while (!interrupted.load()) {
      const std::size_t k = next.fetch_add(1);
      if (k >= args.seeds.size()) break;
      LawResult law = run_law(args.seeds[k], args);
      std::lock_guard lock(mutex);
      if (interrupted.load()) break;
      fmt::print(stderr, "{}\n", progress_line(law));
      laws[k] = std::move(law);
      finished[k] = 1;
    }
    std::lock_guard lock(mutex);
    --running;
    changed.notify_all();
  };
  std::vector<std::thread> workers;
  for (int t = 0; t < worker_count; ++t) workers.emplace_back(work);
  // Ctrl-C is answered from here within 0.1 s: a law's feature search takes no stop
  // callback, so the workers are not waited for; the laws finished so far are reported.
  std::unique_lock lock(mutex);
  while (running > 0 && !interrupted.load()) changed.wait_for(lock, std::chrono::milliseconds(100));
  const bool stopped = interrupted.load();

  std::vector<LawResult> done;
  for (std::size_t k = 0; k < laws.size(); ++k) {
    if (finished[k]) done.push_back(laws[k]);
  }
  if (stopped) fmt::print("interrupted: {} of {} laws finished\n\n", done.size(), args.seeds.size());
  fmt::print("{}", summary_table(done, args.methods));
  if (!args.json.empty()) {
    nlohmann::json out = {{"seeds", args.seed_list},
                          {"settle_s", settle_s},
                          {"smoothing_s", smoothing_s},
                          {"evaluations", args.evaluations},
                          {"training", args.two_runs ? "two-runs" : "cycle"},
                          {"training_noise", args.training_noise},
                          {"bag", args.bag},
                          {"folds_by", to_string(args.folds_by)},
                          {"chamber_air", args.chamber_air ? nlohmann::json{args.chamber_air->first, args.chamber_air->second}
                                                           : nlohmann::json(nullptr)},
                          {"interrupted", stopped},
                          {"laws", laws_json(done)}};
    write_file_atomically(args.json, out.dump(1) + "\n");
  }
  if (stopped) {
    std::fflush(stdout);
    std::_Exit(130);  // the workers still hold their laws; nothing of theirs is reported
  }
  lock.unlock();
  for (auto& worker : workers) worker.join();
  return 0;
}
