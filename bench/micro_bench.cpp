// Micro-benchmarks of the per-sample work of field code, with Google Benchmark:
//   - the RBF decision sum (what an SVR axis costs per sample), ours against the plain
//     scalar loop libsvm's svm-predict runs (Σ c_i exp(-γ‖sv_i − x‖²), one exp call per
//     support vector), for a compressed model (32 vectors), the demo's (527) and a large
//     one (2000), with 2 and 14 features;
//   - Compensator::push per row (3 axes) for the paper's pair (linear), a thermal-node
//     model (lag, hinges, play, memory, Shupe term) and an SVR;
//   - TrailingMean::push, the 100 s smoothing window at 1 Hz.
// After Google Benchmark's own table it prints, for each RBF size, the ratio of the
// scalar loop's time to ours measured in the same run: the exact sum fits use and the
// field's (RbfDecisionFunction::fast, the CPU's widest arithmetic).
//
//   build/bin/micro_bench [--benchmark_min_time=0.2] [--benchmark_filter=Rbf]
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/features/moving_average.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace {

using thermodrift::RbfDecisionFunction;

RbfDecisionFunction random_function(int vectors, int features) {
  std::mt19937_64 random(42);
  std::normal_distribution<double> normal;
  RbfDecisionFunction f;
  f.support_vectors = Eigen::MatrixXd::NullaryExpr(vectors, features, [&] { return normal(random); });
  f.coefficients = Eigen::VectorXd::NullaryExpr(vectors, [&] { return normal(random); });
  f.bias = 0.1;
  f.gamma = 0.5 / features;
  return f;
}

std::vector<double> random_points(int count, int features) {
  std::mt19937_64 random(7);
  std::normal_distribution<double> normal;
  std::vector<double> points(static_cast<std::size_t>(count * features));
  for (double& value : points) value = normal(random);
  return points;
}

// svm-predict's loop (libsvm's Kernel::k_function and svm_predict_values): one exp per vector.
double scalar_sum(const RbfDecisionFunction& f, const double* x) {
  double sum = 0;
  const auto d = f.support_vectors.cols();
  for (Eigen::Index i = 0; i < f.support_vectors.rows(); ++i) {
    double squared = 0;
    for (Eigen::Index j = 0; j < d; ++j) {
      const double difference = f.support_vectors(i, j) - x[j];
      squared += difference * difference;
    }
    sum += f.coefficients[i] * std::exp(-f.gamma * squared);
  }
  return sum + f.bias;
}

constexpr int kPoints = 64;

// One RBF sum per iteration over kPoints points, for a function of state.range(0)
// vectors and state.range(1) features.
template <typename Sum>
void time_rbf(benchmark::State& state, Sum sum) {
  const int vectors = static_cast<int>(state.range(0)), features = static_cast<int>(state.range(1));
  const auto f = random_function(vectors, features);
  const auto points = random_points(kPoints, features);
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(sum(f, &points[(k++ % kPoints) * features]));
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_RbfScalar(benchmark::State& state) { time_rbf(state, scalar_sum); }
// The exact sum (fits, evaluate).
void BM_RbfOurs(benchmark::State& state) {
  time_rbf(state, [](const RbfDecisionFunction& f, const double* x) { return f(x); });
}
// The field's sum (RbfDecisionFunction::fast: AVX-512 or AVX2 with FMA where the CPU has them).
void BM_RbfField(benchmark::State& state) {
  time_rbf(state, [](const RbfDecisionFunction& f, const double* x) { return f.fast(x); });
}

void rbf_sizes(benchmark::internal::Benchmark* b) {
  for (const auto& [vectors, features] : std::vector<std::pair<int, int>>{{32, 2}, {527, 2}, {2000, 2}, {527, 14}}) {
    b->Args({vectors, features});
  }
}
BENCHMARK(BM_RbfScalar)->Apply(rbf_sizes);
BENCHMARK(BM_RbfOurs)->Apply(rbf_sizes);
BENCHMARK(BM_RbfField)->Apply(rbf_sizes);

// One simulated 1 Hz cycle and models fitted on it once, for the compensator rows.
struct Fixture {
  thermodrift::ChamberLog log;
  std::map<std::string, thermodrift::DriftModel> models;

  static const Fixture& get() {
    static const Fixture fixture = [] {
      thermodrift::sim::SimulatorOptions simulation;
      simulation.cycles = 1;
      Fixture f;
      f.log = thermodrift::sim::to_chamber_log(thermodrift::sim::simulate(simulation));
      auto fit = [&](thermodrift::ModelKind model, std::vector<std::string> terms) {
        thermodrift::CalibrationOptions options;
        options.model = model;
        options.terms = std::move(terms);
        options.svr.C = 10;
        options.svr.gamma = 0.5;
        options.svr.epsilon = 0.05;
        return thermodrift::calibrate({f.log}, {}, options).model;
      };
      f.models["paper_linear"] = fit(thermodrift::ModelKind::linear, {"dT", "rate"});
      f.models["node_linear"] = fit(thermodrift::ModelKind::linear, {"lag:600", "hinge:600:-20", "hinge:600:0", "hinge:600:20", "lagrate:600",
                                               "rate", "play:600:1", "dir:900:600", "gradrate:600:120"});
      f.models["paper_svr"] = fit(thermodrift::ModelKind::svr, {"dT", "rate"});
      return f;
    }();
    return fixture;
  }
};

void BM_CompensatorPush(benchmark::State& state, const std::string& model) {
  const Fixture& fixture = Fixture::get();
  thermodrift::Compensator compensator(fixture.models.at(model));
  const auto& log = fixture.log;
  std::vector<double> gyro(3), temperature(3);
  std::size_t row = 0;
  double offset = 0;  // time keeps increasing when the log starts over
  for (auto _ : state) {
    if (row == log.rows()) row = 0, offset += log.time.back() + 1;
    for (std::size_t a = 0; a < 3; ++a) gyro[a] = log.gyro[a][row], temperature[a] = log.temperature[a][row];
    benchmark::DoNotOptimize(compensator.push(log.time[row] + offset, gyro, temperature).ready);
    ++row;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["support_vectors"] = [&] {
    const auto* svr = std::get_if<thermodrift::SvrModel>(&fixture.models.at(model).axes[0].model);
    return svr != nullptr ? static_cast<double>(svr->function.support_vectors.rows()) : 0.0;
  }();
}
BENCHMARK_CAPTURE(BM_CompensatorPush, paper_linear, std::string("paper_linear"));
BENCHMARK_CAPTURE(BM_CompensatorPush, node_linear, std::string("node_linear"));
BENCHMARK_CAPTURE(BM_CompensatorPush, paper_svr, std::string("paper_svr"));

void BM_TrailingMean(benchmark::State& state) {
  thermodrift::TrailingMean mean(100);
  double time = 0;
  for (auto _ : state) {
    time += 1;
    benchmark::DoNotOptimize(mean.push(time, 20.0 + std::sin(time * 1e-3)));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TrailingMean);

// Google Benchmark's console table, then the scalar/ours ratios of each RBF size.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) times_[run.benchmark_name()] = run.GetAdjustedCPUTime();
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    bool header = false;
    for (const auto& [name, ours] : times_) {
      if (name.rfind("BM_RbfOurs/", 0) != 0) continue;
      const std::string size = name.substr(std::string("BM_RbfOurs/").size());
      const auto scalar = times_.find("BM_RbfScalar/" + size);
      const auto field = times_.find("BM_RbfField/" + size);
      if (scalar == times_.end() || field == times_.end() || ours <= 0 || field->second <= 0) continue;
      if (!header) {
        fmt::print("\nRBF decision sum, same run: the scalar loop (svm-predict's) over ours, exact (fits) | field\n");
        header = true;
      }
      fmt::print("  vectors/features {:<10} {:8.1f} ns / {:8.1f} ns = {:.2f}x | / {:8.1f} ns = {:.2f}x\n", size,
                 scalar->second, ours, scalar->second / ours, field->second, scalar->second / field->second);
    }
  }

 private:
  std::map<std::string, double> times_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
