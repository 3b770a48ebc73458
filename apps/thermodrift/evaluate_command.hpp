// What `thermodrift evaluate --json` prints for chamber logs, built once for the command
// line and the Python package (td.DriftModel.evaluate returns the same object).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/stop_token.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift::cli {

// Metrics of `model` on `logs` (the first `settle` seconds of each log and after each gap
// left out), per axis with the envelope tally and the noise-floor estimate, and per log
// when there are several. Warnings (samples outside the envelope, settling) go to warn().
// `start`: where the logs start (evaluate --log-start; evaluate_axes).
nlohmann::json evaluation_result(const DriftModel& model, const std::string& model_file,
                                 const std::vector<ChamberLog>& logs, double settle, const StopToken& stop,
                                 LogStart start = LogStart::power_on);

}  // namespace thermodrift::cli
