// thermodrift export: the model as a dependency-free C99 header for the navigation
// computer (docs/export.md). Prints the model's size: support vectors, bytes of
// constants, operations per sample, and the state the caller must hold.
#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "commands.hpp"
#include "data_options.hpp"
#include "numbers.hpp"
#include "thermodrift/compensate/c_export.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"

namespace thermodrift::cli {

namespace {

struct ExportArguments {
  std::string model_file;
  std::string out;
  bool single_precision = false;
  double max_rate_hz = 0;  // 0: the model's rate, else 100 Hz
  std::string prefix = "thermodrift";
};

int run_export(const ExportArguments& args) {
  const DriftModel model = load_drift_model(args.model_file);
  CExportOptions options;
  options.single_precision = args.single_precision;
  options.prefix = args.prefix;
  if (args.max_rate_hz != 0) options.max_rate_hz = args.max_rate_hz;
  options.source = args.model_file;
  std::string error;
  if (!options.IsValid(&error)) throw UsageError(error);

  const std::string header = export_c_header(model, options);
  write_file_atomically(args.out, header, {args.model_file});

  if (model.despike) {
    warn("the model was fitted with --despike; the header does not despike: filter isolated outliers before "
         "step (docs/export.md)");
  }
  const double rate = export_max_rate_hz(model, options);
  fmt::print("wrote {} ({}, rings sized for {} Hz)\n", args.out,
             options.single_precision ? "float" : "double", rate);
  fmt::print("{}", model_size(model, options.single_precision).table());
  fmt::print("state: {} bytes per {}_state (ring buffers for {} Hz; lower --max-rate to shrink)\n",
             exported_state_bytes(model, options), options.prefix, rate);
  return 0;
}

}  // namespace

Command add_export(CLI::App& parent) {
  auto args = std::make_shared<ExportArguments>();
  CLI::App* app = parent.add_subcommand("export", "write the model as a dependency-free C99 header");
  app->add_option("--model", args->model_file, "model file written by fit")->required()->check(CLI::ExistingFile);
  app->add_option("--out", args->out, "header to write (FILE.h)")->required();
  app->add_flag("--float", args->single_precision, "single precision constants and arithmetic (expf)");
  app->add_option("--max-rate", args->max_rate_hz,
                  "highest sample rate (Hz) the ring buffers must hold; default: the model's rate, else 100")
      ->check(kPositive);
  app->add_option("--prefix", args->prefix, "prefix of the C identifiers (default thermodrift)");
  return {app, [args] { return run_export(*args); }};
}

}  // namespace thermodrift::cli
