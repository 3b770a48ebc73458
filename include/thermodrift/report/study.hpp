// The paper's study on one log: per axis, each model fitted on the earlier part of the
// log and judged both in-sample (as the paper reports) and on the later, held-out part
// (blocked in time; features streamed through from the start of the log, so the lags and
// the smoothing enter the held-out part as they would on a running device).
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {

struct StudyOptions {
  std::vector<ModelKind> models{ModelKind::linear, ModelKind::stepwise, ModelKind::svr};  // models compared
  CalibrationOptions calibration;           // shared settings; `model` is set per entry of `models`
  std::optional<std::size_t> split_row;     // first held-out row; default: the last 30 % of the log
  double holdout_fraction = 0.3;            // used when split_row is not given
  std::string split_description;            // how the split was chosen, in words; default: from the above
  std::function<void(const std::string&)> progress;  // one line per step; may be empty
  // Other feature terms (or {"auto"}) to fit every model with as well, beside the paper's
  // pair, so the report shows both side by side. Empty: the paper's pair only.
  std::vector<std::string> other_terms;
};

struct ModelStudy {
  ModelKind model = ModelKind::linear;
  std::string features = "dT,rate";        // the terms asked for, comma-separated ("auto": chosen per axis)
  Calibration calibration;                 // fitted on the training part
  std::vector<ResidualMetrics> in_sample;  // per axis, training part
  std::vector<ResidualMetrics> held_out;   // per axis, held-out part
  double seconds = 0;
};

struct Study {
  std::size_t split_row = 0;
  double split_time = 0;
  std::string split_description;
  std::vector<ModelStudy> models;

  nlohmann::json to_json() const;
};

Study run_study(const ChamberLog& log, const LogSpec& spec, const StudyOptions& options);

// The first row at or after `when` (report --split-time): a number of seconds on the log's
// own clock (its time column in s; from the first row when it has none), or an ISO 8601
// stamp for a log whose time column holds stamps (or epoch times). UsageError when it is
// neither, or a stamp for a log without a time column.
std::size_t row_at_time(const ChamberLog& log, std::string_view when);

}  // namespace thermodrift
