// What fit and evaluate print: one JSON object with --json, else a short table.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <optional>

#include "thermodrift/features/noise_floor.hpp"
#include "thermodrift/models/fit_record.hpp"

namespace thermodrift::cli {

// `result` holds an "axes" array whose elements carry name, mse_before, mse_after,
// residual_std, residual_peak_to_peak. Prints it as JSON or as a table under `title`.
// Sets an axis' "noise_floor_estimate" and "mse_after_x_floor" (its "mse_after" over that
// estimate) when the estimate is usable; both are estimates and named so.
void add_noise_floor(nlohmann::json& axis, const NoiseFloorEstimate& floor);

// Sets an axis' "expected_held_out": the blocked-CV MSE of the fit (the tuning's CV
// objective, else the feature search's least-squares CV), what it is, and its ratio to the
// noise-floor estimate when add_noise_floor set one. Nothing when the fit had no CV.
void add_expected_held_out(nlohmann::json& axis, const FitRecord& fit);

// fit's warning for an axis (set up by add_noise_floor and add_expected_held_out) beyond
// kFarFromFloor (tune/calibration.hpp), naming the figure; nothing when it is within or
// there is no estimate. `training_logs`: the logs it was fitted on.
std::optional<std::string> far_from_floor_warning(const nlohmann::json& axis, std::size_t training_logs);

// One line on stdout for an axis' compression record (fit.compressed, SvrModel's
// compress): support vectors before and after, the prediction's change, and the MSE
// before and after when both are given, `measured_on` saying on what.
void print_compression(const std::string& axis, const CompressionRecord& compressed, std::optional<double> mse_before,
                       std::optional<double> mse_after, const std::string& measured_on);

// `result` holds an "axes" array (see above); the table also shows, where an axis has
// them, its training envelope, noise-floor estimate and samples outside the envelope.
void print_axes(const nlohmann::json& result, bool as_json, const std::string& title);

}  // namespace thermodrift::cli
