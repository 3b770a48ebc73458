// Tests of compensate/c_export: the exported C99 header is compiled with
// gcc -std=c99 -Wall -Wextra -Werror -pedantic, run on a simulated log, and compared
// sample by sample with the C++ Compensator (linear and SVR models, double and float,
// warm-up, a gap in time, a device sampling faster than the rings are sized for).
#include "thermodrift/compensate/c_export.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <optional>
#include <string>
#include <vector>

#include "../../support/fitted_model.hpp"
#include "../../support/temp_dir.hpp"
#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift {
namespace {

using testing::TempDir;
using testing::fitted_model;

ChamberLog simulated_log() {
  sim::SimulatorOptions options;
  options.cycles = 1;
  options.rate_hz = 1.0;
  return sim::to_chamber_log(sim::simulate(options));
}

// The log without rows [begin, end): a gap in time the pipeline must restart after.
ChamberLog without_rows(const ChamberLog& log, std::size_t begin, std::size_t end) {
  ChamberLog cut = log;
  auto erase = [&](std::vector<double>& column) {
    column.erase(column.begin() + static_cast<std::ptrdiff_t>(begin), column.begin() + static_cast<std::ptrdiff_t>(end));
  };
  erase(cut.time);
  for (auto& column : cut.gyro) erase(column);
  for (auto& column : cut.temperature) erase(column);
  return cut;
}

// The simulated log with the chamber air as a fourth temperature channel.
ChamberLog with_chamber_channel(const ChamberLog& log) {
  sim::SimulatorOptions options;
  options.cycles = 1;
  options.rate_hz = 1.0;
  const sim::ChamberRun run = sim::simulate(options);
  ChamberLog out = log;
  out.temperature_names.push_back("temp_chamber");
  out.temperature.push_back(run.column("temp_chamber"));
  return out;
}

constexpr const char* kDriver = R"(#include <stdio.h>
#include "model.h"

/* Reads "time gyro... temperature..." lines, prints "ready compensated..." lines. */
int main(int argc, char** argv) {
  static thermodrift_state state;
  double time;
  double gyro[THERMODRIFT_AXES];
  double temperature[THERMODRIFT_TEMPERATURES];
  double compensated[THERMODRIFT_AXES];
  FILE* in;
  int a;
  if (argc != 2 || (in = fopen(argv[1], "r")) == NULL) return 2;
  thermodrift_init(&state);
  while (fscanf(in, "%lf", &time) == 1) {
    int ready;
    for (a = 0; a < THERMODRIFT_AXES; ++a) {
      if (fscanf(in, "%lf", &gyro[a]) != 1) return 3;
    }
    for (a = 0; a < THERMODRIFT_TEMPERATURES; ++a) {
      if (fscanf(in, "%lf", &temperature[a]) != 1) return 3;
    }
    ready = thermodrift_step(&state, time, gyro, temperature, compensated);
    printf("%d", ready);
    for (a = 0; a < THERMODRIFT_AXES; ++a) printf(" %.17g", compensated[a]);
    printf("\n");
  }
  printf("dropped %lu\n", state.dropped_samples);
  printf("state_bytes %lu\n", (unsigned long)sizeof state);
  fclose(in);
  return 0;
}
)";

struct CRun {
  std::vector<int> ready;
  std::vector<std::vector<double>> compensated;  // [row][axis]
  unsigned long dropped = 0;
  unsigned long state_bytes = 0;  // sizeof the state struct as the compiler laid it out
};

// Writes the header, compiles the driver with it under strict C99 and runs it on `log`.
CRun run_exported(const TempDir& dir, const std::string& header, const ChamberLog& log,
                  const std::string& extra_flags = "") {
  dir.write("model.h", header);
  dir.write("driver.c", kDriver);
  std::ostringstream samples;
  samples.precision(17);
  for (std::size_t i = 0; i < log.rows(); ++i) {
    samples << log.time[i];
    for (const auto& gyro : log.gyro) samples << ' ' << gyro[i];
    for (const auto& temperature : log.temperature) samples << ' ' << temperature[i];
    samples << '\n';
  }
  dir.write("samples.txt", samples.str());
  const auto compiled = testing::run_in(
      dir, "gcc -std=c99 -Wall -Wextra -Werror -pedantic -O2 " + extra_flags + " driver.c -o driver -lm");
  EXPECT_EQ(compiled.status, 0) << compiled.err;
  const auto ran = testing::run_in(dir, "./driver samples.txt");
  EXPECT_EQ(ran.status, 0) << ran.err;
  CRun result;
  for (const auto& line : testing::split_lines(ran.out)) {
    std::istringstream in(line);
    if (line.rfind("dropped", 0) == 0 || line.rfind("state_bytes", 0) == 0) {
      std::string word;
      in >> word >> (line[0] == 'd' ? result.dropped : result.state_bytes);
      continue;
    }
    int ready = 0;
    in >> ready;
    std::vector<double> values(log.axes());
    for (double& value : values) {  // strtod: operator>> reads no "nan"
      std::string token;
      in >> token;
      value = std::strtod(token.c_str(), nullptr);
    }
    result.ready.push_back(ready);
    result.compensated.push_back(values);
  }
  return result;
}

struct CppRun {
  std::vector<int> ready;
  std::vector<std::vector<double>> compensated;
  double drift_scale = 0;  // largest |drift| of any axis, °/h
};

CppRun run_compensator(const DriftModel& model, const ChamberLog& log) {
  Compensator compensator(model);
  CppRun result;
  std::vector<double> gyro(log.axes());
  std::vector<double> temperature(log.temperature.size());
  for (std::size_t i = 0; i < log.rows(); ++i) {
    for (std::size_t a = 0; a < log.axes(); ++a) gyro[a] = log.gyro[a][i];
    for (std::size_t c = 0; c < temperature.size(); ++c) temperature[c] = log.temperature[c][i];
    const auto& output = compensator.push(log.time[i], gyro, temperature);
    result.ready.push_back(output.ready ? 1 : 0);
    result.compensated.emplace_back(output.compensated.begin(), output.compensated.end());
    for (double drift : output.drift) result.drift_scale = std::max(result.drift_scale, std::abs(drift));
  }
  return result;
}

// Largest |C - C++| over every sample and axis, relative to the drift's scale.
double largest_relative_difference(const CRun& c, const CppRun& cpp) {
  double largest = 0;
  for (std::size_t i = 0; i < cpp.compensated.size(); ++i) {
    for (std::size_t a = 0; a < cpp.compensated[i].size(); ++a) {
      largest = std::max(largest, std::abs(c.compensated[i][a] - cpp.compensated[i][a]) / cpp.drift_scale);
    }
  }
  return largest;
}

void expect_matches(const DriftModel& model, const ChamberLog& log, bool single_precision, double tolerance) {
  TempDir dir;
  CExportOptions options;
  options.single_precision = single_precision;
  options.max_rate_hz = 1.0;
  const CRun c = run_exported(dir, export_c_header(model, options), log);
  const CppRun cpp = run_compensator(model, log);
  ASSERT_EQ(c.ready.size(), log.rows());
  EXPECT_EQ(c.ready, cpp.ready);
  EXPECT_EQ(c.dropped, 0u);
  ASSERT_GT(cpp.drift_scale, 0.1);
  const double difference = largest_relative_difference(c, cpp);
  EXPECT_LE(difference, tolerance) << (single_precision ? "float" : "double");
  // The size export prints (and writes in the header's comment) is the compiled struct's.
  const double estimated = static_cast<double>(exported_state_bytes(model, options));
  EXPECT_NEAR(estimated / static_cast<double>(c.state_bytes), 1.0, 0.05) << c.state_bytes;
  std::printf("[ info ] %s %s: largest |C - C++| / drift scale (%.3g deg/h) = %.3g\n",
              std::string(to_string(model.axes.front().kind)).c_str(), single_precision ? "float" : "double", cpp.drift_scale,
              difference);
}

// The fixed runtime every header carries is a C file of its own (src/compensate/c_runtime.c):
// it compiles without warnings by itself, in both precisions, with and without channels for
// grad terms, under the flags a navigation computer's build might use; and it refuses to
// compile without its configuration.
TEST(CRuntime, CompilesOnItsOwnInEveryConfiguration) {
  TempDir dir;
  const std::string runtime = std::string(THERMODRIFT_SOURCE_DIR) + "/src/compensate/c_runtime.c";
  for (const int single : {0, 1}) {
    for (const int channels : {0, 2}) {
      std::FILE* file = std::fopen(dir.file("unit.c").c_str(), "w");
      ASSERT_NE(file, nullptr);
      std::fprintf(file,
                   "#include <math.h>\n"
                   "#define TDRT_AXES 3\n#define TDRT_TEMPERATURES 4\n#define TDRT_MAX_RATE_HZ 100.0\n"
                   "#define TDRT_MEAN_CAPACITY 128\n#define TDRT_HISTORY_CAPACITY 128\n#define TDRT_FILTERS 6\n"
                   "#define TDRT_SINGLE_PRECISION %d\n#define TDRT_RAW_INPUTS 0\n#define TDRT_GRAD_CHANNELS %d\n"
                   "#define TDRT_RESUM_INITIAL 64\n#define TDRT_RESUM_JUMP %s\n"
                   "#include \"%s\"\n"
                   "int main(void) {\n  static tdrt_state state;\n  tdrt_init(&state);\n"
                   "  return (int)state.rejected_samples;\n}\n",
                   single, channels, single ? "1e6f" : "1e6", runtime.c_str());
      std::fclose(file);
      const auto compiled = testing::run_in(
          dir, "(gcc -std=c99 -Wall -Wextra -Werror -pedantic -Wshadow -Wconversion -Wno-sign-conversion -O2 unit.c "
               "-o unit -lm && ./unit)");
      EXPECT_EQ(compiled.status, 0) << "single " << single << ", channels " << channels << ":\n" << compiled.err;
    }
  }
  std::FILE* bare = std::fopen(dir.file("bare.c").c_str(), "w");
  ASSERT_NE(bare, nullptr);
  std::fprintf(bare, "#include \"%s\"\n", runtime.c_str());
  std::fclose(bare);
  const auto refused = testing::run_in(dir, "gcc -std=c99 -fsyntax-only bare.c");
  EXPECT_NE(refused.status, 0);
  EXPECT_NE(refused.err.find("the configuration macros come first"), std::string::npos) << refused.err;
}

class CExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    log_ = new ChamberLog(simulated_log());
    linear_ = new DriftModel(fitted_model(*log_, {.kind = "linear"}));
    svr_ = new DriftModel(fitted_model(*log_, {.kind = "svr"}));
  }
  static void TearDownTestSuite() {
    delete svr_;
    delete linear_;
    delete log_;
  }
  static ChamberLog* log_;
  static DriftModel* linear_;
  static DriftModel* svr_;
};
ChamberLog* CExport::log_ = nullptr;
DriftModel* CExport::linear_ = nullptr;
DriftModel* CExport::svr_ = nullptr;

// In float the drift at the sample's time multiplies the difference of the prediction and
// its 10 s lag by the window's lag over 10 s (5 here), and with it their rounding: an SVR's
// sum of kernels is held to 1e-4 of the drift scale, a linear model to 1e-5.
TEST_F(CExport, LinearDoubleMatchesCompensator) { expect_matches(*linear_, *log_, false, 1e-9); }
TEST_F(CExport, LinearFloatMatchesCompensator) { expect_matches(*linear_, *log_, true, 1e-5); }

TEST_F(CExport, SvrDoubleMatchesCompensator) {
  const auto& svr = std::get<SvrModel>(svr_->axes.front().model);
  ASSERT_GT(svr.function.support_vectors.rows(), 10);
  expect_matches(*svr_, *log_, false, 1e-9);
}

TEST_F(CExport, SvrFloatMatchesCompensator) { expect_matches(*svr_, *log_, true, 1e-4); }

// Every thermal-lag atom, with powers and a product, through a gap: the C filters start in
// equilibrium and step exactly as the C++ ones do.
TEST_F(CExport, ThermalLagTermsMatchCompensatorThroughAGap) {
  const std::vector<std::string> terms = {"dT",          "lag:420", "lag:420^2",   "lagrate:420",
                                          "gradrate:420:240", "dir:900", "dir:900:420", "dir:900:0:0.07", "dir:600:420:0.5", "dT*rate",
                                          "hinge:420:-15.5", "hinge:420:12", "hinge:420:12^2*rate",
                                          "lead:300", "leadhinge:300:-5", "leadhinge:300:20*dT"};
  const DriftModel linear = fitted_model(*log_, {.kind = "linear", .terms = terms});
  const DriftModel svr = fitted_model(*log_, {.kind = "svr", .terms = {"lag:420", "lagrate:420", "dir:900:420"}});
  const ChamberLog cut = without_rows(*log_, 5000, 5600);
  expect_matches(linear, cut, false, 1e-9);
  expect_matches(linear, cut, true, 1e-4);
  expect_matches(svr, cut, false, 1e-9);
  expect_matches(svr, cut, true, 1e-4);
}

// The series lags, the node with a zero (lag2, lag2rate, nodehinge), the play (two widths)
// and the node's rate responses the identification offers (its rate times its direction of
// travel, its level times its rate), and the turn-on transient, through a gap (which
// starts the transient again). In
// float the node's lead multiplies the difference of two lag states by TL/T2 (7.5 here), and
// with it their rounding, so float is held to 1e-3 of the drift scale, double to 1e-9.
TEST_F(CExport, NodeTermsMatchCompensatorThroughAGap) {
  const std::vector<std::string> terms = {"lag2:420:120", "lag2rate:420:120", "lagrate:420", "nodehinge:420:120:0:3",
                                          "nodehinge:420:0:900:-4", "nodehinge:420:120:900:5^2*rate", "rate",
                                          "play:420:1.5", "play:900:0.5*rate", "play:420:4",
                                          "lagrate:420*dir:60:420:0.05", "lag:420*lagrate:420",
                                          "lag2rate:420:120*dir:60:420:0.05", "lag2:420:120*lag2rate:420:120",
                                          "on:600", "on:1500"};
  const DriftModel linear = fitted_model(*log_, {.kind = "linear", .terms = terms});
  const ChamberLog cut = without_rows(*log_, 5000, 5600);
  expect_matches(linear, cut, false, 1e-9);
  expect_matches(linear, cut, true, 1e-3);
}

// A partially linear SVR (least squares on a thermal node's terms, the kernel on the
// residual): the header adds the linear part to the kernel sum as the C++ model does.
TEST_F(CExport, PartiallyLinearSvrMatchesCompensator) {
  const DriftModel model = fitted_model(
      *log_, {.kind = "partially_linear",
              .terms = {"lag:420", "hinge:420:-10", "hinge:420:15", "lagrate:420", "rate", "dir:900:420"}});
  ASSERT_TRUE(std::get<SvrModel>(model.axes[0].model).linear_part.has_value());
  expect_matches(model, *log_, false, 1e-9);
  expect_matches(model, *log_, true, 1e-4);
}

// A partially linear SVR whose kernel fit left out (fit.kernel_check): its linear part and
// the kernel's bias, without the kernel's arrays.
TEST_F(CExport, PartiallyLinearSvrWithoutVectorsMatchesCompensator) {
  const DriftModel model =
      fitted_model(*log_, {.kind = "linear_part_only", .terms = {"lag:420", "hinge:420:-10", "lagrate:420", "rate"}});
  ASSERT_EQ(std::get<SvrModel>(model.axes[0].model).function.support_vectors.rows(), 0);
  EXPECT_EQ(export_c_header(model, {}).find("_support_vectors"), std::string::npos);
  expect_matches(model, *log_, false, 1e-9);
  expect_matches(model, *log_, true, 1e-4);
}

// grad:A-B and gradrate:A-B on the chamber air as an extra channel (and on another axis'
// channel), in products too, through a gap: each channel is smoothed in C as in C++.
TEST_F(CExport, ChannelGradientTermsMatchCompensatorThroughAGap) {
  const ChamberLog log = with_chamber_channel(*log_);
  const std::vector<std::string> terms = {"dT", "lag:420", "grad:1-4", "gradrate:1-4", "grad:2-3*dT"};
  const DriftModel linear = fitted_model(log, {.kind = "linear", .terms = terms});
  ASSERT_EQ(linear.extra_temperature_columns, (std::vector<std::string>{"temp_chamber"}));
  const DriftModel svr = fitted_model(log, {.kind = "svr", .terms = {"lag:420", "grad:1-4", "gradrate:1-4"}});
  const ChamberLog cut = without_rows(log, 5000, 5600);
  expect_matches(linear, cut, false, 1e-9);
  expect_matches(linear, cut, true, 1e-4);
  expect_matches(svr, cut, false, 1e-9);
  // The chamber air moves without lag, so its rate in float carries the rounding of a
  // 40 °C mean over a 100 s span (~1e-4 °C/min), which the SVR's kernel scales up:
  // measured 1.7e-4 of the drift scale, 0.001 °/h, a twentieth of the noise floor's RMS.
  expect_matches(svr, cut, true, 5e-4);
  const std::string header = export_c_header(linear, {});
  EXPECT_NE(header.find("#define THERMODRIFT_TEMPERATURES 4"), std::string::npos);
}

// An axis whose node is on another channel than its own (the chamber air, another
// axis' thermometer): the header reads that channel for it, as the compensator does,
// and the model file keeps the choice.
TEST_F(CExport, NodeOnAnotherChannelMatchesCompensator) {
  const ChamberLog log = with_chamber_channel(*log_);
  const std::vector<std::string> terms = {"dT", "lag:420", "lagrate:420", "hinge:420:5", "rate"};
  const DriftModel linear = fitted_model(log, {.kind = "linear", .terms = terms, .node_channels = {3, 2, std::nullopt}});
  ASSERT_EQ(linear.extra_temperature_columns, (std::vector<std::string>{"temp_chamber"}));
  const DriftModel own = fitted_model(log, {.kind = "linear", .terms = terms});
  ASSERT_NE(run_compensator(linear, log).compensated, run_compensator(own, log).compensated)
      << "the channel changed nothing";
  const ChamberLog cut = without_rows(log, 5000, 5600);
  expect_matches(linear, cut, false, 1e-9);
  expect_matches(linear, cut, true, 1e-4);
  const DriftModel reloaded = drift_model_from_json(to_json(linear), "model.json");
  EXPECT_EQ(reloaded.axes[0].pipeline.temperature_channel, std::optional<std::size_t>(3));
  EXPECT_EQ(reloaded.axes[1].pipeline.temperature_channel, std::optional<std::size_t>(2));
  EXPECT_FALSE(reloaded.axes[2].pipeline.temperature_channel.has_value());
  EXPECT_EQ(to_json(linear).dump(), to_json(reloaded).dump());
}

TEST_F(CExport, WarmUpAndGapRestartLikeTheCompensator) {
  // 600 s missing in the middle of a ramp: longer than the 100 s gap threshold.
  const ChamberLog cut = without_rows(*log_, 5000, 5600);
  expect_matches(*svr_, cut, false, 1e-9);
  const CppRun cpp = run_compensator(*svr_, cut);
  // warm-up: 200 s (smooth + rate span) from the start and again from the gap
  for (std::size_t i = 0; i < 400; ++i) {
    const bool warm_at_start = cut.time[i] - cut.time[0] >= 200;
    EXPECT_EQ(cpp.ready[i], warm_at_start ? 1 : 0) << i;
    const bool warm_after_gap = cut.time[5000 + i] - cut.time[5000] >= 200;
    EXPECT_EQ(cpp.ready[5000 + i], warm_after_gap ? 1 : 0) << 5000 + i;
  }
}

struct SpoiledRuns {
  CRun c;        // the header on the spoiled log
  CppRun cpp;    // the compensator on the spoiled log
  CppRun clean;  // the compensator on the log as it was
};

SpoiledRuns run_spoiled(const DriftModel& model, const ChamberLog& spoiled, const ChamberLog& clean) {
  TempDir dir;
  CExportOptions options;
  options.max_rate_hz = 1.0;
  return {run_exported(dir, export_c_header(model, options), spoiled), run_compensator(model, spoiled),
          run_compensator(model, clean)};
}

// Failed sensor reads in the field (NaN, inf, or a finite value beyond the physical ranges
// a log is read with: a corrupted word): the sample is rejected whole, never flagged ready,
// and the state goes on as if it had not come; the header does as the compensator.
TEST_F(CExport, ImplausibleInputsAreRejectedWholeLikeTheCompensator) {
  ChamberLog bad = *log_;
  const std::vector<std::size_t> rejected = {500, 900, 1300, 1700, 1701, 2100, 2300};
  bad.temperature[0][500] = std::numeric_limits<double>::quiet_NaN();
  bad.gyro[1][900] = std::numeric_limits<double>::quiet_NaN();
  bad.temperature[2][1300] = std::numeric_limits<double>::infinity();
  bad.gyro[0][1700] = 1.01 * kMaxRateDph;
  bad.gyro[2][1701] = -1e300;
  bad.temperature[1][2100] = kMinTemperatureC - 0.01;
  bad.temperature[0][2300] = 1e300;
  // The edges of the ranges are readings: kept.
  bad.gyro[0][2500] = bad.gyro[0][2500] > 0 ? kMaxRateDph : -kMaxRateDph;
  const auto [c, cpp, clean] = run_spoiled(*svr_, bad, *log_);
  ASSERT_EQ(c.ready.size(), bad.rows());
  EXPECT_EQ(c.ready, cpp.ready);
  for (std::size_t i = 0; i < bad.rows(); ++i) {
    const bool is_rejected = std::find(rejected.begin(), rejected.end(), i) != rejected.end();
    for (std::size_t a = 0; a < bad.axes(); ++a) {
      if (is_rejected) {
        EXPECT_EQ(cpp.ready[i], 0) << i;
        EXPECT_TRUE(std::isnan(c.compensated[i][a]) && std::isnan(cpp.compensated[i][a])) << i;
        continue;
      }
      if (c.ready[i]) EXPECT_TRUE(std::isfinite(c.compensated[i][a])) << i;
      EXPECT_NEAR(c.compensated[i][a], cpp.compensated[i][a], 1e-9 * cpp.drift_scale) << i;
    }
  }
  // The state was left as it was: well after the rejected samples the output is the clean
  // log's again (a lag that stepped 2 s once, a mean that missed one sample: nearly).
  for (std::size_t a = 0; a < bad.axes(); ++a) {
    EXPECT_NEAR(cpp.compensated[3000][a], clean.compensated[3000][a], 1e-6 * clean.drift_scale) << a;
  }
  EXPECT_EQ(cpp.ready[3000], 1);
}

// One huge temperature that is still a reading (the hot end of the range, 1000 °C, after
// -40 °C) spoils only the samples whose window and rate span hold it, and the slope's 10 s
// lag of the prediction for a while after: the running sum is re-added when it leaves, in
// C++ and in the header alike.
TEST_F(CExport, OneHugeTemperatureDoesNotPoisonLaterSamples) {
  ChamberLog bad = *log_;
  const std::size_t at = 1500;
  ASSERT_GT(bad.rows(), at + 900);
  bad.temperature[0][at] = kMaxTemperatureC;
  const auto [c, cpp, clean] = run_spoiled(*linear_, bad, *log_);
  ASSERT_EQ(c.ready.size(), bad.rows());
  // 1 Hz, a 100 s window and a 100 s rate span: from `at` + 200 on nothing of it is left in
  // the prediction; its slope's lag forgets it by e^-30 over the next 300 s.
  EXPECT_GT(std::abs(cpp.compensated[at + 250][0] - clean.compensated[at + 250][0]), 1e-9 * clean.drift_scale);
  for (std::size_t i = at + 500; i < at + 900; ++i) {
    EXPECT_NEAR(cpp.compensated[i][0], clean.compensated[i][0], 1e-9 * clean.drift_scale) << i;
    EXPECT_NEAR(c.compensated[i][0], clean.compensated[i][0], 1e-9 * clean.drift_scale) << i;
    EXPECT_EQ(c.ready[i], cpp.ready[i]) << i;
  }
}

// A model of a raw-count log: the header takes the values as the log holds them (gyro in
// rad/s before a per-axis scale, temperature counts) and converts them as the reader
// does; the compensator gets the log as the reader converts it.
TEST_F(CExport, RawInputsMatchTheCompensatorOnTheLogAsRead) {
  DriftModel model = *linear_;
  model.gyro_unit = GyroUnit::radps;
  model.scaling = {{0.00390625}, {-231, -230.5, -229}, {0.5, 0.25, 2}};
  const LogSpec spec = model.log_spec();
  ASSERT_EQ(spec.temperature_columns.size(), log_->temperature.size());
  std::string csv = "time_s";
  for (const auto& name : spec.gyro_columns) csv += "," + name;
  for (const auto& name : spec.temperature_columns) csv += "," + name;
  csv += "\n";
  for (std::size_t i = 0; i < log_->rows(); ++i) {
    csv += fmt::format("{}", log_->time[i]);
    for (std::size_t a = 0; a < log_->axes(); ++a) {
      csv += fmt::format(",{:.17g}", log_->gyro[a][i] / degrees_per_hour(model.gyro_unit) / model.scaling.gyro_scale_of(a));
    }
    for (std::size_t c = 0; c < log_->temperature.size(); ++c) {
      csv += fmt::format(",{:.17g}", (log_->temperature[c][i] - model.scaling.temperature_offset_of(c)) /
                                         model.scaling.temperature_scale_of(c));
    }
    csv += "\n";
  }
  TempDir dir;
  const std::string path = dir.write("raw.csv", csv);
  const ChamberLog as_read = read_chamber_log(path, spec);
  // The values as the file holds them: read as °C and °/h, the temperature counts would be
  // beyond the physical range of a temperature.
  ChamberLog raw = as_read;
  CsvReader reader(path);
  for (std::size_t i = 0; const auto row = reader.next(); ++i) {
    const std::size_t axes = raw.axes();
    for (std::size_t a = 0; a < axes; ++a) raw.gyro[a][i] = parse_cell(row->cell(1 + a), path, row->line, 2 + a);
    for (std::size_t c = 0; c < raw.temperature.size(); ++c) {
      raw.temperature[c][i] = parse_cell(row->cell(1 + axes + c), path, row->line, 2 + axes + c);
    }
  }
  EXPECT_NEAR(raw.temperature[0][0], (as_read.temperature[0][0] + 231) * 256, 1e-6);

  for (const bool single : {false, true}) {
    CExportOptions options;
    options.max_rate_hz = 1.0;
    options.single_precision = single;
    const std::string header = export_c_header(model, options);
    EXPECT_NE(header.find("#define THERMODRIFT_RAW_INPUTS 1"), std::string::npos);
    const CRun c = run_exported(dir, header, raw);
    const CppRun cpp = run_compensator(model, as_read);
    ASSERT_EQ(c.ready.size(), raw.rows());
    EXPECT_EQ(c.ready, cpp.ready);
    ASSERT_GT(cpp.drift_scale, 0.1);
    EXPECT_LE(largest_relative_difference(c, cpp), single ? 1e-5 : 1e-9) << (single ? "float" : "double");
  }
  // Fed the converted values instead, the header is far off: it did convert.
  const CRun wrong = run_exported(dir, export_c_header(model, {.max_rate_hz = 1.0}), as_read);
  EXPECT_GT(largest_relative_difference(wrong, run_compensator(model, as_read)), 1.0);
}

TEST_F(CExport, DefaultScalingKeepsTheHeaderTakingDegreesPerHourAndDegreesC) {
  DriftModel model = *linear_;
  model.scaling = {{1}, {0}, {1}};  // written out, but the default
  EXPECT_EQ(export_c_header(model, {}), export_c_header(*linear_, {}));
  EXPECT_NE(export_c_header(model, {}).find("#define THERMODRIFT_RAW_INPUTS 0"), std::string::npos);
}

TEST_F(CExport, DeviceFasterThanMaxRateDropsAndFlagsWithoutOverflow) {
  TempDir dir;
  CExportOptions options;
  options.max_rate_hz = 0.25;  // rings hold 27 of the 100 samples a 100 s window needs at 1 Hz
  const std::string header = export_c_header(*linear_, options);
  ChamberLog head = without_rows(*log_, 2000, log_->rows());
  // With the sanitizers when gcc has them: any write outside a ring fails the run.
  const bool sanitizers = testing::run_in(dir, "echo 'int main(void){return 0;}' > probe.c && "
                                               "gcc -fsanitize=address,undefined probe.c -o probe && ./probe")
                              .status == 0;
  const CRun c = run_exported(dir, header, head, sanitizers ? "-fsanitize=address,undefined -fno-sanitize-recover=all" : "");
  ASSERT_EQ(c.ready.size(), head.rows());
  EXPECT_GT(c.dropped, 1000u);
  // Once a ring is full every step drops a sample and says "not ready".
  EXPECT_TRUE(std::all_of(c.ready.begin(), c.ready.end(), [](int ready) { return ready == 0; }));
  for (const auto& row : c.compensated) {
    for (double value : row) EXPECT_TRUE(std::isfinite(value));
  }
}

TEST_F(CExport, HeaderIsSelfContainedC99) {
  CExportOptions options;
  options.prefix = "imu_drift";
  const std::string header = export_c_header(*svr_, options);
  EXPECT_NE(header.find("static inline int imu_drift_step(imu_drift_state* state, double time"), std::string::npos);
  EXPECT_NE(header.find("#define IMU_DRIFT_AXES 3"), std::string::npos);
  EXPECT_EQ(header.find("malloc"), std::string::npos);
  EXPECT_EQ(header.find("thermodrift_"), std::string::npos);
  std::istringstream lines(header);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("#include", 0) == 0) EXPECT_EQ(line, "#include <math.h>");
    // file-scope objects are const; functions are static inline
    if (line.rfind("static ", 0) == 0) {
      EXPECT_TRUE(line.rfind("static const ", 0) == 0 || line.rfind("static inline ", 0) == 0) << line;
    }
  }
  // The float header calls expf only.
  options.single_precision = true;
  const std::string single = export_c_header(*svr_, options);
  EXPECT_NE(single.find("expf("), std::string::npos);
  EXPECT_EQ(single.find(" exp("), std::string::npos);
}

TEST_F(CExport, RejectsBadOptionsAndLibsvmModels) {
  CExportOptions options;
  options.prefix = "2fast";
  EXPECT_THROW(export_c_header(*linear_, options), UsageError);
  options.prefix = "thermodrift";
  options.max_rate_hz = -1;
  EXPECT_THROW(export_c_header(*linear_, options), UsageError);
  options.max_rate_hz = 1e9;  // 1e11 ring entries
  EXPECT_THROW(export_c_header(*linear_, options), UsageError);
  DriftModel libsvm = *linear_;
  libsvm.axes.front().pipeline = Pipeline::libsvm_input(2);
  EXPECT_THROW(export_c_header(libsvm, CExportOptions{}), UsageError);
}

TEST_F(CExport, ModelSizeCountsSupportVectorsBytesAndOperations) {
  const ModelSize size = model_size(*svr_);
  ASSERT_EQ(size.axes.size(), 3u);
  std::size_t support_vectors = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& svr = std::get<SvrModel>(svr_->axes[a].model);
    const auto sv = static_cast<std::size_t>(svr.function.support_vectors.rows());
    EXPECT_EQ(size.axes[a].support_vectors, sv);
    EXPECT_EQ(size.axes[a].exp_per_sample, sv + 1);  // and the slope's lag of the drift's advance
    EXPECT_GE(size.axes[a].constant_bytes, (sv * 2 + sv) * sizeof(double));
    EXPECT_GE(size.axes[a].flops_per_sample, sv * (3 * 2 + 3));
    support_vectors += sv;
  }
  EXPECT_EQ(size.exp_per_sample(), support_vectors + 3);
  EXPECT_EQ(size.operations_per_sample(), size.flops_per_sample() + support_vectors + 3);
  EXPECT_LT(model_size(*svr_, true).constant_bytes(), size.constant_bytes());
  EXPECT_NE(size.table().find("total"), std::string::npos);
  const ModelSize linear = model_size(*linear_);
  EXPECT_EQ(linear.axes[0].regressors, 5u);
  EXPECT_EQ(linear.exp_per_sample(), 3u);  // the drift's advance, one per axis
}

}  // namespace
}  // namespace thermodrift
