// thermodrift compensate: the input rows with one compensated column per axis. Streams
// row by row through the same Compensator a navigation computer would run.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <memory>

#include "commands.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "thermodrift/compensate/compensator.hpp"
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
  std::size_t not_ready = 0;  // rows in a warm-up
};

int run_compensate(const CompensateArguments& args) {
  if (args.data.files.size() != 1) throw UsageError("compensate takes one --data file");
  const std::string& path = args.data.files.front();
  DriftModel model = load_drift_model(args.model_file);
  const LogSpec spec = args.data.spec_for(model);
  CsvReader reader(path, spec.csv);
  const LogColumns columns = resolve_columns(spec, reader);
  const std::size_t inputs = model.temperature_inputs();
  const bool shared = columns.temperature.size() == 1 && model.extra_temperature_columns.empty();
  if (!shared && columns.temperature.size() != inputs) {
    throw UsageError(model.extra_temperature_columns.empty()
                         ? "give one temperature column for all axes or one per axis"
                         : fmt::format("the model reads {} temperature columns: one per axis, then {}", inputs,
                                       fmt::join(model.extra_temperature_columns, ",")));
  }
  AtomicFile out(args.out, {path, args.model_file});
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
  std::vector<AxisTrust> trust(axes);
  LogSample sample;
  double previous_time = std::nan("");
  std::size_t row_index = 0;
  std::string line;
  while (auto row = reader.next()) {
    if ((row_index & 0xFFF) == 0) throw_if_interrupted();
    if (!read_sample(reader, *row, columns, spec, row_index, previous_time, sample)) continue;
    previous_time = sample.time;
    ++row_index;
    for (std::size_t c = 0; c < inputs; ++c) temperatures[c] = sample.temperature[shared ? 0 : c];
    const auto& result = compensator.push(sample.time, sample.gyro, temperatures);
    line.assign(row->text);
    for (std::size_t a = 0; a < axes; ++a) {
      fmt::format_to(std::back_inserter(line), "{}{:.9g}", delimiter, result.compensated[a]);
    }
    for (std::size_t a = 0; a < axes; ++a) {
      const auto& status = result.axes[a];
      if (status.ready) {
        trust[a].outside.add(status.outside_envelope);
      } else {
        ++trust[a].not_ready;
      }
      if (args.flags) {
        const int flags = (status.ready ? 0 : kFlagNotReady) | (status.outside_envelope.any() ? kFlagOutsideEnvelope : 0);
        fmt::format_to(std::back_inserter(line), "{}{}", delimiter, flags);
      }
    }
    line += '\n';
    stream << line;
  }
  reader.finish();
  for (const auto& warning : reader.warnings()) warn(warning);
  out.commit();
  for (std::size_t a = 0; a < axes; ++a) {
    const auto& axis = compensator.model().axes[a];
    const AxisTrust& t = trust[a];
    // A warm-up at the start is normal: say so only beside an excursion, or when the
    // compensator never became ready at all.
    const bool never_ready = row_index > 0 && t.not_ready == row_index;
    if (t.outside.outside == 0 && !never_ready) continue;
    std::string message = fmt::format("compensate: {}: ", axis.name);
    if (t.outside.outside > 0) {
      message += fmt::format("{} of {} rows outside the training envelope ({}); ", t.outside.outside, row_index,
                             t.outside.describe(*axis.envelope));
    }
    if (never_ready) {
      message += fmt::format("never ready: all {} rows were within the {:g} s warm-up of a start or a gap; ", row_index,
                             axis.pipeline.warm_up_seconds());
    } else if (t.not_ready > 0) {
      message += fmt::format("{} rows not ready (warm-up); ", t.not_ready);
    }
    message.resize(message.size() - 2);
    warn(message);
  }
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
