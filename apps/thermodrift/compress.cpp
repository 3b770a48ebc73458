// thermodrift compress: each SVR axis of a model as at most K support vectors (the reduced
// set, models/svr_reduce.hpp), written as an ordinary model file, so evaluate, compensate
// and export take it unchanged. Prints what it cost: the change of the prediction at the
// support vectors, and with --data the MSE on those logs before and after.
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <memory>
#include <variant>

#include "commands.hpp"
#include "data_options.hpp"
#include "interrupt.hpp"
#include "numbers.hpp"
#include "output.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift::cli {

namespace {

struct CompressArguments {
  std::string model_file;
  std::size_t max_vectors = 32;
  DataOptions data;
  double settle = 0;
  std::string out;
  bool json = false;
};

int run_compress(const CompressArguments& args) {
  std::vector<std::string> inputs{args.model_file};
  inputs.insert(inputs.end(), args.data.files.begin(), args.data.files.end());
  // Opened first, as fit does: an output that cannot be written is refused before the work.
  AtomicFile out(args.out, inputs);
  const DriftModel original = load_drift_model(args.model_file);
  DriftModel compressed = original;
  ReduceOptions reduce;
  reduce.max_vectors = args.max_vectors;
  const StopToken stop = interrupt_token();
  reduce.stop = stop;
  std::size_t svr_axes = 0;
  // SVR axes with fewer than two support vectors: nothing to reduce, said per axis.
  std::map<std::string, std::string> unchanged;
  for (auto& axis : compressed.axes) {
    auto* svr = std::get_if<SvrModel>(&axis.model);
    if (svr == nullptr) continue;
    ++svr_axes;
    // The support vectors are the training samples the model file still holds: the
    // reduced set is fitted at them (standardized units, as the function is).
    const Eigen::MatrixXd points = svr->function.support_vectors;
    if (points.rows() < 2) {
      const bool left_out = axis.fit.kernel_check && !axis.fit.kernel_check->kept;
      const char* plural = points.rows() == 1 ? "" : "s";
      const char* why = left_out ? " (the kernel was left out: the axis is its linear part)" : "";
      unchanged.emplace(axis.name, fmt::format("{} support vector{}, nothing to reduce{}", points.rows(), plural, why));
      continue;
    }
    axis.fit.compressed = compress(*svr, points, reduce);
  }
  if (svr_axes == 0) throw UsageError(fmt::format("{} has no SVR axis: nothing to compress", args.model_file));

  if (!args.data.files.empty()) {
    if (args.data.format != "csv") throw UsageError("compress --data reads chamber logs (--format csv)");
    double warm_up = 0;
    for (const auto& axis : original.axes) warm_up = std::max(warm_up, axis.pipeline.warm_up_seconds());
    const std::vector<ChamberLog> logs = args.data.read(args.data.spec_for(original), warm_up, stop);
    const auto before = evaluate_axes(original, logs, args.settle, stop);
    const auto after = evaluate_axes(compressed, logs, args.settle, stop);
    for (std::size_t a = 0; a < compressed.axes.size(); ++a) {
      auto& record = compressed.axes[a].fit.compressed;
      if (!record) continue;
      // Kept in the model file with the logs' names, so the figure says what it was measured on.
      record->data_mse_before = before[a].metrics.mse_after;
      record->data_mse_after = after[a].metrics.mse_after;
      record->data = args.data.files;
      record->settle_seconds = args.settle;
    }
  }
  save_drift_model(compressed, out);

  nlohmann::json axes = nlohmann::json::array();
  for (const auto& axis : compressed.axes) {
    if (const auto why = unchanged.find(axis.name); why != unchanged.end()) {
      axes.push_back({{"name", axis.name}, {"unchanged", why->second}});
      if (!args.json) fmt::print("{}: {}\n", axis.name, why->second);
    }
    if (!axis.fit.compressed) continue;
    const CompressionRecord& record = *axis.fit.compressed;
    axes.push_back({{"name", axis.name}, {"compressed", to_json(record)}});
    if (!args.json) {
      print_compression(axis.name, record, record.data_mse_before, record.data_mse_after,
                        fmt::format("on {} (held-out if the model was not fitted on it)", fmt::join(args.data.files, ", ")));
    }
  }
  if (args.json) {
    fmt::print("{}\n", nlohmann::json{{"command", "compress"}, {"model_file", args.out}, {"axes", axes}}.dump(1));
  } else {
    fmt::print("wrote {} (at most {} support vectors per SVR axis)\n", args.out, args.max_vectors);
  }
  return 0;
}

}  // namespace

Command add_compress(CLI::App& parent) {
  auto args = std::make_shared<CompressArguments>();
  CLI::App* app = parent.add_subcommand(
      "compress", "each SVR axis as at most K support vectors (a reduced set), for a smaller, faster model");
  app->add_option("--model", args->model_file, "model file written by fit")->required()->check(CLI::ExistingFile);
  app->add_option("--max-vectors", args->max_vectors, "K: support vectors per SVR axis (default 32)")
      ->check(whole_number(1, std::size_t{1} << 20));
  args->data.add_to(*app, false);
  app->add_option("--settle", args->settle,
                  "with --data: leave the first SECONDS of each log out of the metrics, while lags settle")
      ->check(kNonNegative);
  app->add_option("--out", args->out, "model file to write")->required();
  app->add_flag("--json", args->json, "print one JSON object on stdout");
  return {app, [args, app] {
            if (args->data.files.empty()) {  // how to read and score logs: nothing to apply it to
              for (const char* option : {"--settle", "--format", "--time", "--rate", "--gyro", "--temp", "--gyro-unit",
                                         "--time-unit", "--temp-scale", "--temp-offset", "--gyro-scale", "--smooth",
                                         "--despike"}) {
                if (app->count(option)) throw UsageError(fmt::format("{} applies with --data", option));
              }
            }
            return run_compress(*args);
          }};
}

}  // namespace thermodrift::cli
