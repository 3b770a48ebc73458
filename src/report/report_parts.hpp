// Internal to the report module: what the figures and the page are drawn from.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/report/allan.hpp"
#include "thermodrift/stop_token.hpp"

namespace thermodrift::report_detail {

// One axis over the whole log, at the pipeline's ready samples.
struct AxisTrace {
  std::string name;
  std::vector<double> time_s;
  std::vector<double> smoothed;                 // the drift target, °/h
  std::vector<double> true_drift;               // °/h, empty when unknown
  std::vector<std::vector<double>> prediction;  // per model, °/h
  std::vector<double> cross_prediction;         // cross-axis SVR, empty when none
};

struct AllanCurve {
  std::string label;
  std::vector<AllanPoint> points;
};

struct AxisAllan {
  std::string name;
  std::vector<AllanCurve> curves;  // raw first, then one per model
};

struct TuningHistory {
  std::string label;  // "AFSA, gyro_x", "grid, gyro_x"
  std::vector<std::pair<double, double>> points;  // (evaluations, best value)
};

struct FigureInputs {
  const ChamberLog* log = nullptr;
  double split_time = 0;
  std::vector<std::string> model_labels;
  std::size_t svr_index = 0;  // the model the cross-axis figure compares with
  std::vector<AxisTrace> axes;
  std::vector<AxisAllan> allan;
  std::vector<TuningHistory> tuning;
};

struct Figure {
  std::string file;     // relative to the report folder
  std::string title;
  std::string caption;
};

struct FigureOutcome {
  std::vector<Figure> figures;
  bool drawn = false;
  std::string note;  // why not, when not drawn
};

// Writes DIR/figures/*.dat and DIR/figures/figures.gp and runs gnuplot in DIR. Returns
// drawn = false with a note when gnuplot is not installed; throws Error when it fails,
// Interrupted (gnuplot ended) when `stop` asks while it writes or gnuplot runs.
FigureOutcome draw_figures(const FigureInputs& inputs, const std::string& dir, const std::string& gnuplot,
                           const StopToken& stop);

// The page, from the summary (so the page shows exactly summary.json's numbers).
std::string render_html(const nlohmann::json& summary, const FigureOutcome& figures, const std::string& dir);

std::string safe_file_name(const std::string& name);

}  // namespace thermodrift::report_detail
