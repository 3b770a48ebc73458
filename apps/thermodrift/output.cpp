#include "output.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdio>

#include "thermodrift/features/envelope.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift::cli {

void print_compression(const std::string& axis, const CompressionRecord& compressed, std::optional<double> mse_before,
                       std::optional<double> mse_after, const std::string& measured_on) {
  std::string mse;
  if (mse_before && mse_after) {
    const double before = *mse_before, after = *mse_after;
    mse = fmt::format("; MSE {:.6g} -> {:.6g} (deg/h)^2 ({:+.2f} %) {}", before, after,
                      before > 0 ? 100.0 * (after - before) / before : 0.0, measured_on);
  }
  fmt::print("{}: {} support vectors -> {}; prediction changed by {:.3g} deg/h RMS ({:.3g} at most) at {} points{}\n",
             axis, compressed.from_vectors, compressed.to_vectors, compressed.rms_change, compressed.max_change,
             compressed.points, mse);
}

void add_expected_held_out(nlohmann::json& axis, const FitRecord& fit) {
  const auto estimate = expected_held_out(fit);
  if (!estimate) return;
  nlohmann::json expected = {{"cv_mse", estimate->cv_mse}, {"from", estimate->from}};
  if (axis.contains("noise_floor_estimate")) {
    expected["x_floor_estimate"] = estimate->cv_mse / axis["noise_floor_estimate"].get<double>();
  }
  axis["expected_held_out"] = expected;
}

std::optional<std::string> far_from_floor_warning(const nlohmann::json& axis, std::size_t training_logs) {
  const bool held_out = axis.contains("expected_held_out") && axis["expected_held_out"].contains("x_floor_estimate");
  if (!held_out && !axis.contains("mse_after_x_floor")) return std::nullopt;
  const double ratio = held_out ? axis["expected_held_out"]["x_floor_estimate"].get<double>()
                                : axis["mse_after_x_floor"].get<double>();
  const bool searched = axis.contains("feature_selection");  // --features auto
  return thermodrift::far_from_floor_warning({{axis.at("name").get<std::string>(), ratio}}, held_out, searched,
                                             training_logs);
}

void add_noise_floor(nlohmann::json& axis, const NoiseFloorEstimate& floor) {
  if (!floor.usable() || !(floor.variance > 0)) return;
  axis["noise_floor_estimate"] = floor.variance;
  axis["mse_after_x_floor"] = axis.at("mse_after").get<double>() / floor.variance;
}

void print_axes(const nlohmann::json& result, bool as_json, const std::string& title) {
  if (as_json) {
    std::fputs((result.dump(2) + "\n").c_str(), stdout);
    return;
  }
  fmt::print("{}\n", title);
  fmt::print("{:<12} {:>9} {:>14} {:>14} {:>12} {:>12}\n", "axis", "samples", "MSE before", "MSE after",
             "resid std", "resid p-p");
  fmt::print("{:<12} {:>9} {:>14} {:>14} {:>12} {:>12}\n", "", "", "(°/h)²", "(°/h)²", "°/h", "°/h");
  for (const auto& axis : result.at("axes")) {
    fmt::print("{:<12} {:>9} {:>14.6g} {:>14.6g} {:>12.4g} {:>12.4g}\n", axis.at("name").get<std::string>(),
               axis.at("samples").get<std::size_t>(), axis.at("mse_before").get<double>(),
               axis.at("mse_after").get<double>(), axis.at("residual_std").get<double>(),
               axis.at("residual_peak_to_peak").get<double>());
  }
  if (result.contains("runs")) {
    fmt::print("per run:\n");
    for (const auto& run : result["runs"]) {
      for (const auto& axis : run.at("axes")) {
        std::string ratio;
        if (axis.contains("mse_after_x_floor")) ratio = fmt::format(" ({:.3g} × its floor estimate)", axis["mse_after_x_floor"].get<double>());
        fmt::print("  {} {}: {} samples, MSE before {:.6g}, after {:.6g} (°/h)²{}\n", run.at("file").get<std::string>(),
                   axis.at("name").get<std::string>(), axis.at("samples").get<std::size_t>(),
                   axis.at("mse_before").get<double>(), axis.at("mse_after").get<double>(), ratio);
      }
    }
  }
  for (const auto& axis : result.at("axes")) {
    if (!axis.contains("terms")) continue;
    std::string terms;
    for (const auto& term : axis["terms"]) terms += (terms.empty() ? "" : ", ") + term.get<std::string>();
    fmt::print("{} terms: {}\n", axis.at("name").get<std::string>(), terms);
  }
  for (const auto& axis : result.at("axes")) {
    const auto name = axis.at("name").get<std::string>();
    if (axis.contains("training_envelope")) {
      const auto& json = axis["training_envelope"];
      fmt::print("{} training envelope: {}\n", name, TrainingEnvelope::from_json(json, json.at("terms").size()).brief());
    }
    if (axis.contains("noise_floor_estimate")) {
      fmt::print("{} noise floor (estimate, from the log): {:.4g} (°/h)²; MSE after = {:.3g} × that estimate\n", name,
                 axis["noise_floor_estimate"].get<double>(), axis["mse_after_x_floor"].get<double>());
    }
    if (axis.contains("expected_held_out")) {
      const auto& expected = axis["expected_held_out"];
      std::string ratio;
      if (expected.contains("x_floor_estimate")) {
        ratio = fmt::format(" = {:.3g} × the floor estimate", expected["x_floor_estimate"].get<double>());
      }
      const auto from = expected["from"].get<std::string>();
      fmt::print("{} expected held-out MSE: {:.4g} (°/h)²{} (from {}; {})\n", name, expected["cv_mse"].get<double>(),
                 ratio, from,
                 from.find("leave-one-run-out") != std::string::npos
                     ? "each run predicted by a model of the others"
                     : "within this log's kind of programme — another programme can be worse");
    }
    if (axis.contains("running_weight") && result.value("settle_seconds", 0.0) > 0) {
      fmt::print("{} start of the log, estimated from its settling rows: weight of a running start {:.2g} (0: "
                 "power-on, 1: running)\n",
                 name, fmt::join(axis["running_weight"].get<std::vector<double>>(), ", "));
    }
    if (axis.contains("outside_envelope")) {
      fmt::print("{} outside the training envelope: {} of {} samples ({:.1f} %)\n", name,
                 axis["outside_envelope"].get<std::size_t>(), axis.at("samples").get<std::size_t>(),
                 100 * axis["outside_envelope_fraction"].get<double>());
    }
  }
}

}  // namespace thermodrift::cli
