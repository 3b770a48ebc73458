// compensate_bench: prediction speed of our compensator against libsvm's svm-predict on
// the same model and samples, and `thermodrift compensate` streaming a 50 Hz, 3-axis,
// 24-hour log (rows per second, peak resident memory of the child). One command, one
// table; `--quick` for a smaller run. See bench/README.md and docs/export.md.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/compensate/c_export.hpp"
#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/models/svr_model.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "../tests/support/fitted_model.hpp"

namespace fs = std::filesystem;
using namespace thermodrift;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// One model per axis on a 1 Hz cycle: the paper's pipeline, linear or ε-SVR with fixed
// C = 10, γ = 0.5, ε = 0.05 (standardized units), the export tests' fixture.
DriftModel fit(const ChamberLog& log, ModelKind kind) {
  return testing::fitted_model(log, {.kind = std::string(to_string(kind)), .squares = false});
}

struct ChildRun {
  int status = -1;
  double seconds = 0;
  long peak_rss_kb = 0;
};

// fork/exec + wait4: wall time and the child's own peak resident set size.
ChildRun run_child(const std::vector<std::string>& argv, const std::string& stdout_path) {
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);  // the child must not inherit (and print again) our buffered output
  const auto start = Clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    if (std::freopen(stdout_path.c_str(), "w", stdout) == nullptr) _exit(126);
    execv(args[0], args.data());
    _exit(127);
  }
  ChildRun run;
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  run.seconds = seconds_since(start);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.peak_rss_kb = usage.ru_maxrss;
  return run;
}

// libsvm's model format for our ε-SVR: f = Σ coef·K − rho, so rho = −bias.
void write_libsvm_model(const RbfDecisionFunction& function, const std::string& path) {
  std::ofstream out(path);
  out << "svm_type epsilon_svr\nkernel_type rbf\n";
  out << fmt::format("gamma {:.17g}\nnr_class 2\ntotal_sv {}\nrho {:.17g}\nSV\n", function.gamma,
                     function.support_vectors.rows(), -function.bias);
  for (Eigen::Index k = 0; k < function.support_vectors.rows(); ++k) {
    out << fmt::format("{:.17g}", function.coefficients(k));
    for (Eigen::Index j = 0; j < function.support_vectors.cols(); ++j) {
      out << fmt::format(" {}:{:.17g}", j + 1, function.support_vectors(k, j));
    }
    out << '\n';
  }
}

std::string self_directory() { return fs::canonical("/proc/self/exe").parent_path().string(); }

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: compensate_bench [--quick]\n");
      return 2;
    }
  }
  const fs::path dir = fs::temp_directory_path() / fmt::format("thermodrift-compensate-bench-{}", getpid());
  fs::create_directories(dir);
  const std::string binary = self_directory() + "/thermodrift";

  // ---- (a) predictions per second: ours vs svm-predict, same model and samples ----
  sim::SimulatorOptions training;
  training.cycles = 1;
  training.rate_hz = 1.0;
  const ChamberLog training_log = sim::to_chamber_log(sim::simulate(training));
  const DriftModel svr_model = fit(training_log, ModelKind::svr);
  const DriftModel linear_model = fit(training_log, ModelKind::linear);
  // The same SVR as a reduced set of 32 vectors per axis (thermodrift compress --max-vectors 32).
  DriftModel compressed_model = svr_model;
  std::vector<double> compression_rms;
  for (auto& compressed_axis : compressed_model.axes) {
    auto& compressed_svr = std::get<SvrModel>(compressed_axis.model);
    ReduceOptions reduce;
    reduce.max_vectors = 32;
    const Eigen::MatrixXd points = compressed_svr.function.support_vectors;
    compression_rms.push_back(compress(compressed_svr, points, reduce).rms_change);
  }
  const auto& axis = svr_model.axes.front();
  const auto& svr = std::get<SvrModel>(axis.model);
  const FeatureTable table = build_feature_table(axis.pipeline, training_log, 0, 0, false);
  const Eigen::Index repeat = quick ? 1 : 5;
  Eigen::MatrixXd features(table.features.rows() * repeat, table.features.cols());
  for (Eigen::Index r = 0; r < repeat; ++r) features.middleRows(r * table.features.rows(), table.features.rows()) = table.features;
  const Eigen::MatrixXd standardized = svr.scaling.features(features);
  const auto n = static_cast<std::size_t>(features.rows());

  fmt::print("compensate_bench{}: SVR model C=10 gamma=0.5 eps=0.05 on a simulated 1 Hz cycle\n",
             quick ? " --quick" : "");
  fmt::print("{}", model_size(svr_model).table());
  fmt::print("\n{:<52} {:>12} {:>14} {:>10}\n", "(a) prediction, axis x, same samples", "samples", "per sample", "ratio");

  // Ours: SvrModel::predict on raw features (standardization included), repeated to >= 1 s.
  std::vector<double> ours(n);
  double our_seconds = 0;
  std::size_t our_predictions = 0;
  const auto start = Clock::now();
  do {
    std::vector<double> row(static_cast<std::size_t>(features.cols()));
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < row.size(); ++j) row[j] = features(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      ours[i] = svr.predict(row);
    }
    our_predictions += n;
    our_seconds = seconds_since(start);
  } while (our_seconds < 1.0);
  const double our_per_sample = our_seconds / static_cast<double>(our_predictions);
  // The exact sum (the same bits on every x86-64): SvrModel::predict on a matrix, as fit,
  // evaluate and the report predict.
  double exact_seconds = 0;
  std::size_t exact_predictions = 0;
  {
    const auto begin = Clock::now();
    double sink = 0;
    do {
      sink += svr.predict(features).sum();
      exact_predictions += n;
      exact_seconds = seconds_since(begin);
    } while (exact_seconds < 1.0);
    if (sink == 42.0) std::puts("");  // keep the loop
  }
  const double exact_per_sample = exact_seconds / static_cast<double>(exact_predictions);
  double compressed_per_sample = 0;
  std::size_t compressed_predictions = 0;
  {
    const auto& small = std::get<SvrModel>(compressed_model.axes.front().model);
    std::vector<double> row(static_cast<std::size_t>(features.cols()));
    std::size_t predictions = 0;
    double sink = 0;
    const auto begin = Clock::now();
    while (seconds_since(begin) < 1.0) {
      for (std::size_t i = 0; i < n; ++i, ++predictions) {
        for (std::size_t j = 0; j < row.size(); ++j) row[j] = features(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        sink += small.predict(row);
      }
    }
    compressed_per_sample = seconds_since(begin) / static_cast<double>(predictions);
    compressed_predictions = predictions;
    if (sink == 42.0) std::puts("");  // keep the loop
  }

  // libsvm: standardized samples and model in its formats; svm-predict end to end.
  const std::string model_path = (dir / "svr.model").string();
  const std::string data_path = (dir / "samples.libsvm").string();
  const std::string predictions_path = (dir / "predictions.txt").string();
  write_libsvm_model(svr.function, model_path);
  {
    std::ofstream data(data_path);
    for (Eigen::Index i = 0; i < standardized.rows(); ++i) {
      data << 0;
      for (Eigen::Index j = 0; j < standardized.cols(); ++j) data << fmt::format(" {}:{:.17g}", j + 1, standardized(i, j));
      data << '\n';
    }
  }
  const ChildRun libsvm = run_child({"/usr/bin/svm-predict", data_path, model_path, predictions_path},
                                    (dir / "svm-predict.out").string());
  const double libsvm_per_sample = libsvm.seconds / static_cast<double>(n);
  double largest_difference = 0;
  {
    std::ifstream in(predictions_path);
    double value = 0;
    for (std::size_t i = 0; i < n && in >> value; ++i) {
      const double ours_standardized = (ours[i] - svr.scaling.target_mean) / svr.scaling.target_scale;
      largest_difference = std::max(largest_difference, std::abs(value - ours_standardized));
    }
  }
  // The whole Compensator: 3 axes, pipeline + model, per pushed row.
  double compensator_per_row = 0;
  {
    Compensator compensator(svr_model);
    std::vector<double> gyro(3), temperature(3);
    const auto begin = Clock::now();
    std::size_t rows = 0;
    double sink = 0;
    while (seconds_since(begin) < 1.0) {
      for (std::size_t i = 0; i < training_log.rows(); ++i, ++rows) {
        for (std::size_t a = 0; a < 3; ++a) {
          gyro[a] = training_log.gyro[a][i];
          temperature[a] = training_log.temperature[a][i];
        }
        sink += compensator.push(training_log.time[i], gyro, temperature).compensated[0];
      }
      compensator.reset();
    }
    compensator_per_row = seconds_since(begin) / static_cast<double>(rows);
    if (sink == 42.0) std::puts("");  // keep the loop
  }
  fmt::print("{:<52} {:>12} {:>11.3f} us {:>10}\n", "svm-predict (exec, parse, predict, write)", n,
             libsvm_per_sample * 1e6, "1.0x");
  fmt::print("{:<52} {:>12} {:>11.3f} us {:>9.1f}x\n",
             fmt::format("ours: SvrModel::predict, field sum ({})", RbfDecisionFunction::fast_arithmetic()),
             our_predictions, our_per_sample * 1e6, libsvm_per_sample / our_per_sample);
  fmt::print("{:<52} {:>12} {:>11.3f} us {:>9.1f}x\n", "ours: the same, exact sum (as fit and evaluate)",
             exact_predictions, exact_per_sample * 1e6, libsvm_per_sample / exact_per_sample);
  fmt::print("{:<52} {:>12} {:>11.3f} us {:>9.1f}x\n",
             fmt::format("ours: the same, compressed to {} vectors",
                         std::get<SvrModel>(compressed_model.axes.front().model).function.support_vectors.rows()),
             compressed_predictions, compressed_per_sample * 1e6, libsvm_per_sample / compressed_per_sample);
  fmt::print("  compressed: prediction changed by {:.3g} / {:.3g} / {:.3g} deg/h RMS at the support vectors\n",
             compression_rms[0], compression_rms[1], compression_rms[2]);
  fmt::print("{:<52} {:>12} {:>11.3f} us\n", "ours: Compensator::push, 3 axes (per row)", training_log.rows(),
             compensator_per_row * 1e6);
  fmt::print("  svm-predict: {:.3f} s total, exit {}; predictions agree within {:.2g} (standardized units)\n",
             libsvm.seconds, libsvm.status, largest_difference);
  fmt::print("  predictions per second: ours {:.3g}, svm-predict {:.3g}\n", 1.0 / our_per_sample,
             1.0 / libsvm_per_sample);

  // ---- (b) thermodrift compensate streaming a 50 Hz 3-axis log ----
  sim::SimulatorOptions field;
  field.rate_hz = 50;
  field.cycles = quick ? 1 : 4;  // one cycle is 6 h 20 min: 4 cycles > 24 h, > 4 million rows
  field.seed = 7;
  const std::string log_path = (dir / "field.csv").string();
  std::size_t field_rows = 0;
  double log_hours = 0;
  {
    const sim::ChamberRun run = sim::simulate(field);
    field_rows = run.rows();
    log_hours = static_cast<double>(field_rows) / field.rate_hz / 3600.0;
    std::ofstream out(log_path);
    sim::write_csv(run, out);
  }
  const auto log_bytes = fs::file_size(log_path);
  fmt::print("\n(b) thermodrift compensate: {} rows, {:.1f} h at 50 Hz, 3 axes, {:.0f} MB CSV\n", field_rows,
             log_hours, static_cast<double>(log_bytes) / 1e6);
  fmt::print("{:<30} {:>10} {:>14} {:>14} {:>12}\n", "model", "seconds", "rows/s", "peak RSS", "vs linear");
  const std::vector<std::pair<std::string, const DriftModel*>> models = {
      {"linear", &linear_model}, {"svr", &svr_model}, {"svr-32", &compressed_model}};
  double linear_rows_per_second = 0;
  for (const auto& [kind, model] : models) {
    const std::string model_file = (dir / (kind + ".json")).string();
    save_drift_model(*model, model_file);
    const ChildRun run = run_child({binary, "compensate", "--model", model_file, "--data", log_path, "--out",
                                    (dir / "compensated.csv").string()},
                                   (dir / "compensate.out").string());
    const double rows_per_second = static_cast<double>(field_rows) / run.seconds;
    if (kind == "linear") linear_rows_per_second = rows_per_second;
    const std::string label = kind == "svr" ? "svr (SV per axis above)" : kind == "svr-32" ? "svr compressed to 32 SV" : kind;
    fmt::print("{:<30} {:>10.1f} {:>14.0f} {:>11.1f} MB {:>11.2f}x{}\n", label, run.seconds, rows_per_second,
               static_cast<double>(run.peak_rss_kb) / 1024.0, rows_per_second / linear_rows_per_second,
               run.status == 0 ? "" : fmt::format("  FAILED exit {}", run.status));
    fs::remove(dir / "compensated.csv");
  }
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  return 0;
}
