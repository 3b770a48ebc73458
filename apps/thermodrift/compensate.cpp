// thermodrift compensate: the input rows with one compensated column per axis. Streams
// row by row through the same Compensator a navigation computer would run.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/compensate/readiness.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/io/csv_reader.hpp"

namespace thermodrift::cli {

namespace {

struct CompensateArguments {
  DataOptions data;
  std::string model_file;
  std::string out;
  bool flags = false;
};

// Bits of the <axis>_flags column.
constexpr int kFlagNotReady = 1;
constexpr int kFlagOutsideEnvelope = 2;

// What compensate tells about one axis at the end.
struct AxisTrust {
  EnvelopeTally outside;      // ready rows against the training envelope
  ReadinessTally readiness;   // rows in a warm-up, and why
};

// One warning per axis with rows outside the training envelope; one line when no row
// was ready, saying why (a warm-up at the start is normal: not said otherwise).
void report_trust(const DriftModel& model, const std::vector<AxisTrust>& trust, std::size_t rows) {
  for (std::size_t a = 0; a < trust.size(); ++a) {
    const AxisTrust& t = trust[a];
    if (t.outside.outside == 0) continue;
    std::string message = fmt::format("compensate: {}: {} of {} rows outside the training envelope ({})",
                                      model.axes[a].name, t.outside.outside, rows,
                                      t.outside.describe(*model.axes[a].envelope));
    if (t.readiness.not_ready() > 0) message += fmt::format("; {} rows not ready (warm-up)", t.readiness.not_ready());
    warn(message);
  }
  std::vector<std::size_t> never_ready;
  for (std::size_t a = 0; a < trust.size(); ++a) {
    if (rows > 0 && trust[a].readiness.ready() == 0) never_ready.push_back(a);
  }
  if (never_ready.empty()) return;
  const std::size_t first = never_ready.front();
  std::string message = fmt::format("compensate: {}: never ready: all {} rows were within the {:g} s warm-up of a start "
                                    "or a gap; {}",
                                    model.axes[first].name, rows, model.axes[first].pipeline.warm_up_seconds(),
                                    trust[first].readiness.never_ready_reason());
  if (never_ready.size() > 1) {
    std::vector<std::string> others;
    for (auto it = never_ready.begin() + 1; it != never_ready.end(); ++it) others.push_back(model.axes[*it].name);
    message += fmt::format(" (likewise {})", fmt::join(others, ", "));
  }
  warn(message);
}

int run_compensate(const CompensateArguments& args) {
  if (args.data.files.size() != 1) throw UsageError("compensate takes one --data file");
  const std::string& path = args.data.files.front();
  // Opened first: a reader of a FIFO gets an end of file, not a wait for ever, when the
  // model or the log is refused below (a file output is not replaced then).
  AtomicFile out(args.out, {path, args.model_file});
  DriftModel model = load_drift_model(args.model_file);
  const LogSpec spec = args.data.spec_for(model);
  CsvReader reader(path, spec.csv);
  LogSampleReader samples(reader, spec);
  const LogColumns& columns = samples.columns();
  const std::size_t inputs = model.temperature_inputs();
  const bool shared = columns.temperature.size() == 1 && model.extra_temperature_columns.empty();
  if (!shared && columns.temperature.size() != inputs) {
    throw UsageError(model.extra_temperature_columns.empty()
                         ? "give one temperature column for all axes or one per axis"
                         : fmt::format("the model reads {} temperature columns: one per axis, then {}", inputs,
                                       fmt::join(model.extra_temperature_columns, ",")));
  }
  auto& stream = out.stream();
  const std::string delimiter(1, reader.delimiter());
  if (reader.has_header()) {
    stream << fmt::format("{}", fmt::join(reader.header(), delimiter));
    for (const auto& axis : model.axes) stream << delimiter << axis.name << "_comp_dph";
    if (args.flags) {
      for (const auto& axis : model.axes) stream << delimiter << axis.name << "_flags";
    }
    stream << '\n';
  }

  Compensator compensator(std::move(model));
  const std::size_t axes = compensator.axes();
  std::vector<double> temperatures(inputs);
  std::vector<AxisTrust> trust;
  for (const auto& axis : compensator.model().axes) trust.push_back({{}, ReadinessTally(axis.pipeline)});
  std::size_t not_ready_rows = 0;
  LogSample sample;
  std::string line;
  const StopToken stop = interrupt_token();
  // The echoed row is the file's text: times relative to the first row never reach it.
  while (auto row = samples.next(sample)) {
    if ((samples.rows() & 0xFFF) == 1) stop.throw_if_requested("compensation");
    for (std::size_t c = 0; c < inputs; ++c) temperatures[c] = sample.temperature[shared ? 0 : c];
    const auto& result = compensator.push(sample.time, sample.gyro, temperatures);
    if (!result.ready) ++not_ready_rows;
    line.assign(row->text);
    for (std::size_t a = 0; a < axes; ++a) {
      // A model overflowing on this row: the Compensator flags it not ready, and the column
      // says NaN as the exported step does, never "inf", which reads as a number.
      const double compensated = result.compensated[a];
      if (std::isfinite(compensated)) {
        fmt::format_to(std::back_inserter(line), "{}{:.9g}", delimiter, compensated);
      } else {
        fmt::format_to(std::back_inserter(line), "{}nan", delimiter);
      }
    }
    for (std::size_t a = 0; a < axes; ++a) {
      const auto& status = result.axes[a];
      if (status.ready) trust[a].outside.add(status.outside_envelope);
      trust[a].readiness.add(sample.time, status.since_start, status.ready);
      if (args.flags) {
        const int flags = (status.ready ? 0 : kFlagNotReady) | (status.outside_envelope.any() ? kFlagOutsideEnvelope : 0);
        fmt::format_to(std::back_inserter(line), "{}{}", delimiter, flags);
      }
    }
    line += '\n';
    stream << line;
  }
  reader.finish();
  // A log shorter than the 4,096 rows between the asks above is never asked about after
  // its first row: a stop during it must still leave nothing written.
  stop.throw_if_requested("compensation");
  for (const auto& warning : reader.warnings()) warn(warning);
  out.commit();
  const std::size_t rows = samples.rows();
  report_trust(compensator.model(), trust, rows);
  if (spec.despike) {
    note_despiked(path, samples.columns().gyro_names, samples.despiked_gyro(), samples.columns().temperature_names,
                  samples.despiked_temperature());
  }
  std::fprintf(stderr, "thermodrift: %s: %zu of %zu rows not ready (warm-up / gaps)\n", path.c_str(), not_ready_rows,
               rows);
  return 0;
}

}  // namespace

Command add_compensate(CLI::App& parent) {
  auto args = std::make_shared<CompensateArguments>();
  CLI::App* app = parent.add_subcommand("compensate", "write the log with compensated gyro columns (°/h)");
  app->add_option("--model", args->model_file, "model file written by fit")->required()->check(CLI::ExistingFile);
  args->data.add_to(*app);
  app->add_option("--out", args->out, "output CSV")->required();
  app->add_flag("--flags", args->flags,
                "append per axis a column <axis>_flags: 0 ok, 1 not ready (warm-up), 2 outside the training "
                "envelope (bitwise OR)");
  return {app, [args] { return run_compensate(*args); }};
}

}  // namespace thermodrift::cli
