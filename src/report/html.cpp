// report.html: one page that opens from disk, figures inline as SVG (each also linked to
// its file beside the page), every number taken from the summary.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "report_parts.hpp"
#include "thermodrift/report/report.hpp"

namespace thermodrift::report_detail {

namespace {

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string num(const nlohmann::json& value) {
  return value.is_number() ? format_number(value.get<double>()) : std::string("–");
}

std::string inline_svg(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto start = text.find("<svg");
  return start == std::string::npos ? std::string() : text.substr(start);
}

void table(std::ostringstream& page, const nlohmann::json& t, bool floor_known, const std::string& caption) {
  page << "<table>\n<caption>" << caption << "</caption>\n<tr><th rowspan=\"2\">axis</th><th rowspan=\"2\">original drift<br>MSE</th>";
  const int per_model = floor_known ? 4 : 3;
  for (const auto& column : t["columns"]) {
    page << "<th colspan=\"" << per_model << "\">" << escape(column["label"].get<std::string>()) << "</th>";
  }
  if (floor_known) page << "<th rowspan=\"2\">noise floor<br>(°/h)²</th>";
  page << "</tr>\n<tr>";
  for (std::size_t i = 0; i < t["columns"].size(); ++i) {
    page << "<th>MSE (°/h)²</th>" << (floor_known ? "<th>× floor</th>" : "") << "<th>std °/h</th><th>p-p °/h</th>";
  }
  page << "</tr>\n";
  for (const auto& row : t["rows"]) {
    page << "<tr><td>" << escape(row["axis"].get<std::string>()) << "</td><td>" << num(row["original_mse"]) << "</td>";
    for (const auto& cell : row["models"]) {
      page << "<td class=\"mse\">" << num(cell["mse"]) << "</td>";
      if (floor_known) page << "<td>" << num(cell["ratio_to_floor"]) << "</td>";
      page << "<td>" << num(cell["residual_std"]) << "</td><td>" << num(cell["residual_peak_to_peak"]) << "</td>";
    }
    if (floor_known) page << "<td>" << num(row["noise_floor"]) << "</td>";
    page << "</tr>\n";
  }
  page << "</table>\n";
}

// What each model's blocked CV on the training part expected, against what the held-out
// part gave: how far the estimate `fit` prints can be trusted on this log.
void expected_against_held_out(std::ostringstream& page, const nlohmann::json& t) {
  std::ostringstream rows;
  for (const auto& row : t["rows"]) {
    for (std::size_t i = 0; i < row["models"].size(); ++i) {
      const auto& cell = row["models"][i];
      if (!cell.contains("expected_mse")) continue;
      rows << "<tr><td>" << escape(row["axis"].get<std::string>()) << "</td><td>"
           << escape(t["columns"][i]["label"].get<std::string>()) << "</td><td>" << num(cell["expected_mse"])
           << "</td><td>" << num(cell.value("expected_x_floor_estimate", nlohmann::json())) << "</td><td>"
           << num(cell["mse"]) << "</td><td>" << escape(cell["expected_from"].get<std::string>()) << "</td></tr>\n";
    }
  }
  if (rows.str().empty()) return;
  page << "<table>\n<caption>Expected held-out MSE (blocked CV on the training part, as <code>fit</code> prints it) "
          "against the held-out MSE</caption>\n<tr><th>axis</th><th>model</th><th>expected (°/h)²</th>"
          "<th>expected × floor estimate</th><th>held-out (°/h)²</th><th>expected from</th></tr>\n"
       << rows.str() << "</table>\n";
}

// The paragraph saying which table to believe, with this log's numbers.
std::string verdict(const nlohmann::json& summary, bool floor_known) {
  const auto& in = summary["tables"]["in_sample"];
  const auto& out = summary["tables"]["held_out"];
  std::ostringstream text;
  text << "<p class=\"verdict\"><b>Which table to believe: the held-out one.</b> "
          "The in-sample table is the paper's Table 1: each model is judged on the very samples it was fitted to. "
          "A flexible model (the SVR) can follow the noise left after smoothing as well as the drift, so its "
          "in-sample MSE says how well it memorised, not how well it will compensate the next run. The held-out "
          "table judges the same models on a later, contiguous part of the log they never saw ("
       << escape(summary["split"]["description"].get<std::string>())
       << "), which is what a gyro in service meets.";
  std::size_t svr_col = in["columns"].size();
  for (std::size_t c = 0; c < in["columns"].size(); ++c) {
    if (in["columns"][c]["model"] == "svr") svr_col = c;
  }
  if (svr_col < in["columns"].size()) {
    text << " Here, SVR residual MSE per axis, in-sample → held-out:";
    for (std::size_t a = 0; a < in["rows"].size(); ++a) {
      const auto& row_in = in["rows"][a];
      const auto& row_out = out["rows"][a];
      text << (a ? ";" : "") << " " << escape(row_in["axis"].get<std::string>()) << " "
           << num(row_in["models"][svr_col]["mse"]) << " → " << num(row_out["models"][svr_col]["mse"]) << " (°/h)²";
      if (floor_known) {
        text << " (" << num(row_in["models"][svr_col]["ratio_to_floor"]) << " → "
             << num(row_out["models"][svr_col]["ratio_to_floor"]) << " × the noise floor)";
      }
    }
    text << ".";
  }
  if (floor_known) {
    text << " The noise floor is the variance of the smoothed noise (output minus the true drift), which no "
            "drift model can remove: an in-sample MSE at or below it means the fit learned noise, and only "
            "the held-out ratio to the floor tells how much real drift is left.";
  } else {
    text << " Without the true drift the noise floor is unknown; an in-sample MSE near the gyro's own smoothed "
            "bias instability (e.g. 1e-4 (°/h)² = (0.01 °/h)²) is a sign that the fit learned noise.";
  }
  text << "</p>\n";
  return text.str();
}

}  // namespace

std::string render_html(const nlohmann::json& summary, const FigureOutcome& figures, const std::string& dir) {
  const bool floor_known = summary["data"]["true_drift_known"].get<bool>();
  std::ostringstream page;
  page << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
       << escape(summary["title"].get<std::string>()) << "</title>\n<style>\n"
       << "body{font-family:Helvetica,Arial,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\n"
          "table{border-collapse:collapse;margin:1em 0;font-size:0.9em}caption{text-align:left;font-weight:bold;padding:0.3em 0}\n"
          "td,th{border:1px solid #bbb;padding:0.25em 0.5em;text-align:right}th{background:#f0f0f0}\n"
          "td:first-child{text-align:left}figure{margin:1.5em 0}figure svg{max-width:100%;height:auto}\n"
          ".verdict{background:#fff8e0;border-left:4px solid #e0a000;padding:0.7em 1em}\n"
          "pre{background:#f6f6f6;padding:0.5em;overflow-x:auto;font-size:0.85em}\n</style></head><body>\n";
  page << "<h1>" << escape(summary["title"].get<std::string>()) << "</h1>\n";
  page << "<p>The paper: Wu Junwei, Miao Lingjuan, Li Fusheng, Shen Jun, <i>Compensation method of FOG temperature "
          "drift with improved support vector machine</i>, Infrared and Laser Engineering 47(5), 0522003 (2018), "
          "doi:10.3788/IRLA201847.0522003.</p>\n";
  const auto& data = summary["data"];
  page << "<p>Log <code>" << escape(data["source"].get<std::string>()) << "</code>: " << data["rows"].get<std::size_t>()
       << " rows over " << num(data["duration_s"].get<double>() / 3600.0) << " h at " << num(data["sample_rate_hz"])
       << " Hz; " << data["axes"].size() << " gyro axes, " << data["temperatures"].size() << " temperature channels."
       << (summary["command"].get<std::string>().empty()
               ? std::string()
               : " Made by <code>" + escape(summary["command"].get<std::string>()) + "</code>.")
       << "</p>\n";
  const auto& split = summary["split"];
  page << "<p><b>Split in time:</b> " << escape(split["description"].get<std::string>()) << ". Models are fitted on rows 0–"
       << split["row"].get<std::size_t>() - 1 << " (t &lt; " << num(split["time_s"]) << " s) and judged held-out on the "
       << split["held_out_rows"].get<std::size_t>() << " rows from t = " << num(split["time_s"]) << " s on.</p>\n";
  page << verdict(summary, floor_known);

  page << "<h2>Residual MSE of the smoothed drift (the paper's Table 1)</h2>\n"
          "<p>MSE of the original drift is its variance (what removing a constant bias leaves); each model column is "
          "the mean square of the smoothed output minus the predicted drift, with the residual's standard deviation "
          "and peak-to-peak beside it.";
  if (floor_known) page << " “× floor” is the MSE divided by the noise floor of the same part of the log.";
  page << "</p>\n";
  table(page, summary["tables"]["in_sample"], floor_known, "Table 1 — in-sample (fitted and judged on the training part, as the paper reports)");
  table(page, summary["tables"]["held_out"], floor_known, "Table 2 — held-out (judged on the later part the models never saw)");
  expected_against_held_out(page, summary["tables"]["held_out"]);
  if (summary.contains("warnings") && !summary["warnings"].empty()) {
    page << "<p>Far from the noise floor (as <code>fit</code> warns; docs/generalization.md, “Far from the "
            "floor”):</p>\n<ul>\n";
    for (const auto& warning : summary["warnings"]) page << "<li>" << escape(warning.get<std::string>()) << "</li>\n";
    page << "</ul>\n";
  }

  if (summary.contains("feature_selection") && !summary["feature_selection"].empty()) {
    const auto& first = summary["feature_selection"][0]["selection"];
    if (first.value("method", "greedy") == "thermal_node") {
      page << "<h2>Feature selection</h2>\n<p>Terms identified per axis on the training part as one thermal "
              "node: its lag (or two lags in series, or a lag with a lead) on a grid limited to what the log can "
              "identify, a piecewise-linear map of its temperature, its rate and the sensor's, then a Shupe term, "
              "a memory, a play or a second lag while each cuts the score by more than "
           << num(100.0 * first["min_gain"].get<double>())
           << " %, every time constant refined (docs/features.md). The score is the least-squares fit's blocked "
              "cross-validation: "
           << (first.value("cv_score", std::string("pooled")) == "geometric_mean"
                   ? "the geometric mean of the held-out blocks' MSEs (the typical block), "
                   : "the MSE pooled over the held-out blocks, ")
           << "the <code>average</code> step and the <b>chosen</b> rows the MSE pooled over the blocks. For the SVR "
              "the terms are its linear part and the kernel fits the residual. These CV figures are selection "
              "scores on the training part; the held-out table says how well the terms generalize.</p>\n";
    } else {
      page << "<h2>Feature selection</h2>\n<p>Terms chosen per axis on the training part by forward selection over "
              "lags and thermal terms, scored by the blocked cross-validation MSE of least squares (time constants "
              "refined as each candidate is tried); a term is kept only if it cuts that MSE by more than "
           << num(100.0 * first["min_gain"].get<double>())
           << " %. For the SVR, the last sets the search settled on are then judged by an AFSA-tuned SVR's own "
              "blocked CV (<code>svr</code> steps), with the same penalty (docs/features.md). These CV figures are "
              "selection scores on the training part; the held-out table says how well the terms generalize.</p>\n";
    }
    for (const auto& entry : summary["feature_selection"]) {
      const auto& selection = entry["selection"];
      page << "<table><caption>" << escape(entry["axis"].get<std::string>()) << " ("
           << selection["candidates_scored"].get<std::size_t>() << " candidate sets scored)</caption>\n"
           << "<tr><th>step</th><th>term</th><th>CV score, (°/h)²</th></tr>\n"
           << "<tr><td>start</td><td>constant</td><td>" << num(selection["start_mse"]) << "</td></tr>\n";
      for (const auto& step : selection["path"]) {
        page << "<tr><td>" << escape(step["action"].get<std::string>()) << "</td><td><code>"
             << escape(step["term"].get<std::string>()) << "</code></td><td>" << num(step["cv_mse"]) << "</td></tr>\n";
      }
      for (const auto& chosen : entry["chosen"]) {
        std::string terms;
        for (const auto& t : chosen["terms"]) terms += (terms.empty() ? "" : ", ") + t.get<std::string>();
        page << "<tr><td><b>chosen</b>, " << escape(chosen["label"].get<std::string>()) << "</td><td><code>"
             << escape(terms) << "</code></td><td>" << num(chosen["cv_mse"]) << "</td></tr>\n";
        if (chosen.contains("kernel_check")) {
          const auto& check = chosen["kernel_check"];
          page << "<tr><td>kernel, nested CV</td><td>" << escape(kernel_check_text(check)) << "</td><td>"
               << num(check["with_kernel_mse"]) << "</td></tr>\n";
        }
      }
      page << "</table>\n";
    }
  }

  if (!summary["cross_axis"].empty()) {
    page << "<h2>Cross-axis experiment</h2>\n<table><caption>SVR trained on the other axes, tested on the one left out "
            "(held-out part)</caption>\n<tr><th>left out</th><th>trained on</th><th>original MSE</th>"
            "<th>cross-axis MSE</th><th>own-axis SVR MSE</th></tr>\n";
    for (const auto& c : summary["cross_axis"]) {
      std::string trained;
      for (const auto& name : c["trained_on"]) trained += (trained.empty() ? "" : ", ") + name.get<std::string>();
      page << "<tr><td>" << escape(c["left_out"].get<std::string>()) << "</td><td>" << escape(trained) << "</td><td>"
           << num(c["held_out_original_mse"]) << "</td><td>" << num(c["held_out_mse"]) << "</td><td>"
           << num(c["own_axis_held_out_mse"]) << "</td></tr>\n";
    }
    page << "</table>\n";
  }

  page << "<h2>Figures</h2>\n";
  if (!figures.drawn) page << "<p><b>No figures:</b> " << escape(figures.note) << "</p>\n";
  for (const auto& f : figures.figures) {
    if (!figures.drawn) break;
    page << "<figure id=\"" << escape(f.file) << "\"><figcaption><b>" << escape(f.title) << ".</b> " << escape(f.caption)
         << " (<a href=\"" << escape(f.file) << "\">" << escape(f.file) << "</a>)</figcaption>\n"
         << inline_svg((std::filesystem::path(dir) / f.file).string()) << "</figure>\n";
  }
  if (figures.drawn && summary["parameters"]["svr_per_axis"].is_array()) {
    bool any_history = false;
    for (const auto& f : figures.figures) any_history = any_history || f.file == "tuning.svg";
    if (!any_history) {
      page << "<p>No tuning convergence figure: the SVR fits carry no tuning history (fixed C and σ).</p>\n";
    }
  }

  const auto& p = summary["parameters"];
  page << "<h2>Parameters</h2>\n<ul>\n<li>Smoothing: trailing moving average over " << num(p["smooth_seconds"])
       << " s on gyro and temperature; dT/dt as a backward difference over " << num(p["rate_span_seconds"])
       << " s.</li>\n<li>Features: ";
  for (std::size_t i = 0; i < p["terms"].size(); ++i) page << (i ? ", " : "") << escape(p["terms"][i].get<std::string>());
  page << " (ΔT from the training part's mean temperature; dT/dt in °C/min); fitting keeps every "
       << p["decimation"].get<std::size_t>() << "th sample.</li>\n<li>Seed " << p["seed"].get<std::uint64_t>()
       << ", threads " << p["threads"].get<int>() << ".</li>\n</ul>\n";
  page << "<table><caption>SVR per axis (ε-SVR, RBF kernel; standardized feature and target units)</caption>\n"
          "<tr><th>axis</th><th>C</th><th>σ</th><th>γ = 1/(2σ²)</th><th>ε</th><th>fits while tuning</th><th>solver</th></tr>\n";
  for (const auto& axis : p["svr_per_axis"]) {
    const auto params = axis.value("params", nlohmann::json::object());
    page << "<tr><td>" << escape(axis["axis"].get<std::string>()) << "</td><td>" << num(params.value("C", nlohmann::json()))
         << "</td><td>" << num(params.value("sigma", nlohmann::json())) << "</td><td>"
         << num(params.value("gamma", nlohmann::json())) << "</td><td>" << num(params.value("epsilon", nlohmann::json()))
         << "</td><td>" << num(axis.value("evaluations", nlohmann::json())) << "</td><td>"
         << escape(axis.contains("solver") ? axis["solver"].value("termination", std::string()) : std::string())
         << "</td></tr>\n";
  }
  page << "</table>\n";
  for (const auto& axis : p["svr_per_axis"]) {
    if (!axis.contains("tuning")) continue;
    nlohmann::json shown = axis["tuning"];
    if (shown.is_object()) shown.erase("history");
    page << "<p>" << escape(axis["axis"].get<std::string>()) << ", tuning:</p><pre>" << escape(shown.dump(1))
         << "</pre>\n";
  }

  page << "<h2>Time taken</h2>\n<table><tr><th>step</th><th>seconds</th></tr>\n";
  for (const auto& t : summary["timings"]) {
    page << "<tr><td>" << escape(t["step"].get<std::string>()) << "</td><td>" << num(t["seconds"]) << "</td></tr>\n";
  }
  page << "<tr><td><b>total</b></td><td><b>" << num(summary["total_seconds"]) << "</b></td></tr>\n</table>\n";
  page << "<p>All numbers are also in <a href=\"summary.json\">summary.json</a>; the fitted models in model_*.json; "
          "the figures' gnuplot script and data in figures/.</p>\n</body></html>\n";
  return page.str();
}

}  // namespace thermodrift::report_detail
