// ε-SVR: our solver against libsvm's svm-train on the same data in one run.
//
//   build/bin/svr_bench [--quick] [--skip-libsvm-corner] [--no-100k] [--threads N]
//                       [--cache-mb MB] [--tolerance T] [--epsilon E]
//                       [--only N [--C C] [--gamma G] [--auto]] [--no-libsvm] [--verbose]
//
// --only N fits only the ordinary case at n = N (or at --C/--gamma; with --auto by the
// default kernel choice, which takes the low-rank factor where it is complete), for profiling;
// --verbose adds our summary line (kernel columns, SVs) under each row.
//
// Data: standardized chamber-like (ΔT, dT/dt) with a smooth nonlinear drift plus noise,
// as in tests/reference. svm-train is timed as a process (wall time, including reading
// its input file, a few ms); ours in process. Prints one table; docs/svr.md has figures.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/io/libsvm_reader.hpp"
#include "thermodrift/models/svr.hpp"
#include "../tests/support/chamber_like.hpp"

using namespace thermodrift;

namespace {

using Data = testing::SvrData;
using testing::chamber_like;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct LibsvmResult {
  bool ran = false;
  double seconds = 0;
  double objective = 0;
  long iterations = 0;
  bool capped = false;
  long peak_rss_kb = 0;
};

LibsvmResult run_svm_train(const std::string& data_path, const SvrOptions& options) {
  const std::string model_path = data_path + ".model";
  const std::string command =
      fmt::format("/usr/bin/svm-train -s 3 -t 2 -c {:.17g} -g {:.17g} -p {:.17g} -e {:.17g} -m {} '{}' '{}' 2>&1",
                  options.C, options.gamma, options.epsilon, options.tolerance, options.cache_mb, data_path,
                  model_path);
  const auto start = std::chrono::steady_clock::now();
  FILE* pipe = ::popen(command.c_str(), "r");
  LibsvmResult result;
  if (!pipe) return result;
  std::string output;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  if (::pclose(pipe) != 0) return result;
  result.seconds = seconds_since(start);
  result.ran = true;
  auto number_after = [&](const std::string& key) {
    const auto at = output.rfind(key);
    return at == std::string::npos ? std::nan("") : std::stod(output.substr(at + key.size()));
  };
  result.objective = number_after("obj = ");
  result.iterations = static_cast<long>(number_after("#iter = "));
  result.capped = output.find("reaching max number of iterations") != std::string::npos;
  return result;
}

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / fmt::format("thermodrift_svr_bench_{}_{}", ::getpid(), name))
      .string();
}

void print_header() {
  fmt::print("{:<26} {:>7} {:>8} {:>6} | {:>9} {:>10} {:>17} | {:>8} {:>10} {:>17} {:>15} | {:>7}\n", "case", "n",
             "C", "gamma", "libsvm s", "iter", "obj", "ours s", "iter", "obj", "termination", "ratio");
}

bool verbose = false;

void compare(const std::string& name, const Data& data, SvrOptions options, bool run_libsvm) {
  LibsvmResult libsvm;
  if (run_libsvm) {
    const std::string path = temp_path(name + ".libsvm");
    {
      std::ofstream out(path);
      write_libsvm(out, data.samples, data.targets);
    }
    libsvm = run_svm_train(path, options);
    std::filesystem::remove(path);
    std::filesystem::remove(path + ".model");
  }
  const SvrFit fit = SvrTrainer(options).train(data.samples, data.targets);
  const SvrSummary& s = fit.summary;
  const std::string libsvm_seconds = libsvm.ran ? fmt::format("{:.3f}", libsvm.seconds) : "skipped";
  const std::string libsvm_iterations =
      libsvm.ran ? fmt::format("{}{}", libsvm.iterations, libsvm.capped ? "(cap)" : "") : "-";
  const std::string libsvm_objective = libsvm.ran ? fmt::format("{:.6f}", libsvm.objective) : "-";
  const std::string ratio = libsvm.ran ? fmt::format("{:.1f}x", libsvm.seconds / s.seconds) : "-";
  fmt::print("{:<26} {:>7} {:>8g} {:>6g} | {:>9} {:>10} {:>17} | {:>8.3f} {:>10} {:>17.6f} {:>15} | {:>7}\n", name,
             data.samples.rows(), options.C, options.gamma, libsvm_seconds, libsvm_iterations, libsvm_objective,
             s.seconds, s.iterations, s.dual_objective, to_string(s.termination), ratio);
  if (verbose) fmt::print("    {}\n", s.BriefReport());
  std::fflush(stdout);
}

// A fit in a child process, so that its peak resident memory is its own.
void bounded_memory_fit(int count, SvrOptions options) {
  std::fflush(stdout);
  int channel[2];
  if (::pipe(channel) != 0) return;
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(channel[0]);
    const Data data = chamber_like(count, 7);
    const SvrFit fit = SvrTrainer(options).train(data.samples, data.targets);
    const std::string report = fit.summary.BriefReport();
    if (::write(channel[1], report.data(), report.size()) < 0) ::_exit(1);
    ::_exit(0);
  }
  ::close(channel[1]);
  std::string report;
  char buffer[512];
  for (ssize_t got; (got = ::read(channel[0], buffer, sizeof buffer)) > 0;) report.append(buffer, static_cast<std::size_t>(got));
  ::close(channel[0]);
  int status = 0;
  struct rusage usage {};
  ::wait4(child, &status, 0, &usage);
  fmt::print("n = {} ({}) with --cache-mb {}: {}\n  peak RSS of the fitting process: {:.1f} MiB "
             "(data {:.1f} MiB, cache budget {} MiB)\n",
             count, to_string(options.approximation), options.cache_mb, report, static_cast<double>(usage.ru_maxrss) / 1024.0,
             count * 3 * 8 / 1048576.0, options.cache_mb);
}

// The Nyström fit against the exact one on the same samples: time, the ε-SVR primal
// objective ½‖f‖²_H + C·Σ max(0, |y − f| − ε) of each function, and how far their
// predictions differ, on the training samples and on a later stretch of the same series.
void nystrom_against_exact(int count, SvrOptions options) {
  const Data data = chamber_like(count, 11);
  const Data later = chamber_like(count + count / 4, 11);  // the same series, a quarter longer
  const Eigen::MatrixXd tail = later.samples.bottomRows(count / 4);
  auto primal = [&](const RbfDecisionFunction& f) {
    return f.primal_objective(data.samples, data.targets, options.C, options.epsilon);
  };
  options.approximation = SvrApproximation::exact;
  const SvrFit exact = SvrTrainer(options).train(data.samples, data.targets);
  options.approximation = SvrApproximation::nystrom;
  const SvrFit nystrom = SvrTrainer(options).train(data.samples, data.targets);
  const double primal_exact = primal(exact.function), primal_nystrom = primal(nystrom.function);
  const auto rms = [](const Eigen::VectorXd& d) { return std::sqrt(d.squaredNorm() / static_cast<double>(d.size())); };
  fmt::print("n = {:6d}, C = {:g}, γ = {:g}: exact {:7.2f} s ({} SV), Nyström {:6.2f} s ({} landmarks, mean kernel "
             "residual {:.1e}) = {:.1f}x; primal objective {:.6g} vs {:.6g} ({:+.3f} %); prediction difference RMS "
             "{:.2e} in-sample, {:.2e} on the later quarter (targets' SD 1)\n",
             count, options.C, options.gamma, exact.summary.seconds, exact.summary.support_vectors,
             nystrom.summary.seconds, nystrom.summary.landmarks, nystrom.summary.kernel_residual,
             exact.summary.seconds / nystrom.summary.seconds, primal_exact, primal_nystrom,
             100 * (primal_nystrom - primal_exact) / primal_exact,
             rms(exact.function.predict(data.samples) - nystrom.function.predict(data.samples)),
             rms(exact.function.predict(tail) - nystrom.function.predict(tail)));
  if (verbose) fmt::print("  exact: {}\n  Nyström: {}\n", exact.summary.BriefReport(), nystrom.summary.BriefReport());
}

// Many fits on the same samples, as the tuner makes them: cold vs warm start along C,
// and with/without precomputed squared distances along gamma.
void repeated_fits(const Data& data, SvrOptions options) {
  const std::vector<double> penalties{50, 70, 100, 140, 200, 280};
  const SvrDataset plain(data.samples);
  double cold_seconds = 0, warm_seconds = 0;
  long cold_iterations = 0, warm_iterations = 0;
  double worst_difference = 0;
  SvrFit previous;
  for (std::size_t k = 0; k < penalties.size(); ++k) {
    options.C = penalties[k];
    const SvrTrainer trainer(options);
    const SvrFit cold = trainer.train(plain, data.targets);
    cold_seconds += cold.summary.seconds;
    cold_iterations += cold.summary.iterations;
    if (k > 0) {
      const SvrFit warm = trainer.train(plain, data.targets, &previous);
      warm_seconds += warm.summary.seconds;
      warm_iterations += warm.summary.iterations;
      worst_difference = std::max(worst_difference, std::abs(warm.summary.dual_objective - cold.summary.dual_objective) /
                                                        std::abs(cold.summary.dual_objective));
      previous = warm;
    } else {
      warm_seconds += cold.summary.seconds;
      warm_iterations += cold.summary.iterations;
      previous = cold;
    }
  }
  fmt::print("C path 50..280 (6 fits, gamma {}): cold {:.3f} s / {} iterations, warm {:.3f} s / {} iterations "
             "(objectives agree to {:.1e} relative)\n",
             options.gamma, cold_seconds, cold_iterations, warm_seconds, warm_iterations, worst_difference);

  const std::vector<double> gammas{0.01, 0.03, 0.1, 0.3, 1, 3};
  options.C = 10;
  auto start = std::chrono::steady_clock::now();
  for (double gamma : gammas) {
    options.gamma = gamma;
    (void)SvrTrainer(options).train(plain, data.targets);
  }
  const double from_samples = seconds_since(start);
  start = std::chrono::steady_clock::now();
  const SvrDataset with_distances(data.samples, 1024);
  const double precompute = seconds_since(start);
  for (double gamma : gammas) {
    options.gamma = gamma;
    (void)SvrTrainer(options).train(with_distances, data.targets);
  }
  const double from_distances = seconds_since(start);
  fmt::print("gamma path 0.01..3 (6 fits, C 10): kernel from samples {:.3f} s, from precomputed distances "
             "{:.3f} s (of which {:.3f} s computing them once)\n",
             from_samples, from_distances, precompute);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, skip_libsvm_corner = false, run_100k = true, run_libsvm = true;
  int only = 0;
  double only_C = 215, only_gamma = 0.046;
  bool only_auto = false;
  SvrOptions base;
  base.threads = 2;
  base.cache_mb = 200;
  base.tolerance = 1e-3;
  base.epsilon = 0.1;
  base.approximation = SvrApproximation::exact;  // the rows against svm-train compare the exact solver
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    auto value = [&]() {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", argument.c_str());
        std::exit(2);
      }
      return std::string(argv[++i]);
    };
    if (argument == "--quick") quick = true;
    else if (argument == "--skip-libsvm-corner") skip_libsvm_corner = true;
    else if (argument == "--no-100k") run_100k = false;
    else if (argument == "--threads") base.threads = std::stoi(value());
    else if (argument == "--cache-mb") base.cache_mb = std::stod(value());
    else if (argument == "--tolerance") base.tolerance = std::stod(value());
    else if (argument == "--epsilon") base.epsilon = std::stod(value());
    else if (argument == "--auto") only_auto = true;
    else if (argument == "--only") only = std::stoi(value());
    else if (argument == "--no-libsvm") run_libsvm = false;
    else if (argument == "--C") only_C = std::stod(value());
    else if (argument == "--gamma") only_gamma = std::stod(value());
    else if (argument == "--verbose") verbose = true;
    else {
      std::fprintf(stderr, "usage: svr_bench [--quick] [--skip-libsvm-corner] [--no-100k] [--threads N] "
                           "[--cache-mb MB] [--tolerance T] [--epsilon E] [--only N [--C C] [--gamma G] [--auto]] "
                           "[--no-libsvm] [--verbose]\n");
      return 2;
    }
  }
  if (quick) skip_libsvm_corner = true;

  fmt::print("ε-SVR, RBF kernel, epsilon {}, tolerance {}, cache {} MiB, our threads {}; "
             "ratio = svm-train time / our time\n\n",
             base.epsilon, base.tolerance, base.cache_mb, base.threads);
  print_header();
  if (only > 0) {
    SvrOptions ordinary = base;
    ordinary.C = only_C;
    ordinary.gamma = only_gamma;
    if (only_auto) ordinary.approximation = SvrApproximation::automatic;
    compare(only_auto ? "only, auto" : "only", chamber_like(only, only == 2271 ? 3 : 1), ordinary, run_libsvm);
    return 0;
  }
  std::vector<int> sizes{2000, 5000, 20000};
  if (quick) sizes = {2000, 5000};
  for (int count : sizes) {
    SvrOptions ordinary = base;
    ordinary.C = 215;
    ordinary.gamma = 0.046;
    compare(fmt::format("ordinary"), chamber_like(count, 1), ordinary, run_libsvm);
  }
  // The same data by the default kernel choice: at γ = 0.046 on two features the kernel
  // matrix is of low rank, so `automatic` solves the exact problem through a complete
  // factor (docs/svr.md, "Wide kernels"); its objective is the primal's, equal to the
  // dual's at the optimum.
  for (int count : sizes) {
    SvrOptions automatic = base;
    automatic.approximation = SvrApproximation::automatic;
    automatic.C = 215;
    automatic.gamma = 0.046;
    compare("ordinary, auto (low rank)", chamber_like(count, 1), automatic, run_libsvm);
  }
  {
    SvrOptions ordinary = base;
    ordinary.C = 1;
    ordinary.gamma = 0.5;
    compare("libsvm defaults", chamber_like(quick ? 2000 : 5000, 2), ordinary, run_libsvm);
  }
  SvrOptions corner = base;
  corner.C = 1e4;
  corner.gamma = 100;
  compare("corner", chamber_like(2271, 3), corner, run_libsvm && !skip_libsvm_corner);
  fmt::print("\n");

  repeated_fits(chamber_like(quick ? 1000 : 2271, 4), base);
  fmt::print("\n");

  if (run_100k) {
    SvrOptions large = base;
    large.C = 215;
    large.gamma = 0.046;
    large.cache_mb = 100;
    bounded_memory_fit(quick ? 30000 : 100000, large);
    // The full-rate row of docs/svr.md: a 5-cycle 1 Hz log's worth without decimation, by
    // the Nyström fit that `fit --decimate 1` takes beyond SvrOptions::exact_limit samples.
    SvrOptions full_rate = base;
    full_rate.approximation = SvrApproximation::nystrom;
    full_rate.C = 10;
    full_rate.gamma = gamma_of_sigma(1.0);
    bounded_memory_fit(quick ? 30000 : 100000, full_rate);
    full_rate.C = 215;
    full_rate.gamma = 0.046;
    bounded_memory_fit(quick ? 30000 : 100000, full_rate);
  }
  fmt::print("\nNyström ({} landmarks at most) against the exact solver:\n", base.landmarks);
  for (const int count : quick ? std::vector<int>{3000} : std::vector<int>{3000, 10000}) {
    SvrOptions options = base;
    for (const auto& [C, gamma] : {std::pair{10.0, gamma_of_sigma(1.0)}, std::pair{215.0, 0.046}}) {
      options.C = C, options.gamma = gamma;
      nystrom_against_exact(count, options);
    }
  }
  return 0;
}
