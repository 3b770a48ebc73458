// thermodrift report end to end on a small simulated log, and the Allan deviation
// against the white-noise law.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/report/allan.hpp"
#include "thermodrift/report/report.hpp"

namespace thermodrift {
namespace {

using testing::TempDir;

std::string binary() { return THERMODRIFT_BINARY; }

bool gnuplot_installed() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

// White noise of standard deviation σ at rate f has σ_A(τ) = σ / √(τ f). With N samples
// and cluster m, the overlapping estimate's relative error is about √(1/(N/m)) (χ²
// with ~1.5 N/m degrees of freedom); at m ≤ N/100 that is well inside 15 %.
TEST(AllanDeviation, FollowsTheWhiteNoiseLaw) {
  for (const double rate : {1.0, 10.0}) {
    std::mt19937_64 generator(42);
    std::normal_distribution<double> normal(0.0, 2.0);
    std::vector<double> series(200'000);
    for (auto& value : series) value = 5.0 + normal(generator);  // a constant bias does not matter
    const auto points = overlapping_allan_deviation(series, rate, 10, 0.25);
    ASSERT_GT(points.size(), 30U);
    EXPECT_DOUBLE_EQ(points.front().tau_s, 1.0 / rate);
    for (std::size_t i = 1; i < points.size(); ++i) EXPECT_GT(points[i].tau_s, points[i - 1].tau_s);
    for (const auto& p : points) {
      const double m = p.tau_s * rate;
      if (m > static_cast<double>(series.size()) / 100) continue;
      const double expected = 2.0 / std::sqrt(p.tau_s * rate);
      EXPECT_NEAR(p.deviation / expected, 1.0, 0.15) << "tau " << p.tau_s << " rate " << rate;
      EXPECT_EQ(p.terms, series.size() - 2 * static_cast<std::size_t>(std::lround(m)) + 1);
    }
  }
}

TEST(AllanDeviation, LinearRampAndEdgeCases) {
  // A rate ramp y_k = a k has second differences of the phase a m² τ0², so σ(τ) = a m τ0 / √2.
  std::vector<double> ramp(1000);
  for (std::size_t k = 0; k < ramp.size(); ++k) ramp[k] = 0.01 * static_cast<double>(k);
  for (const auto& p : overlapping_allan_deviation(ramp, 1.0)) {
    EXPECT_NEAR(p.deviation, 0.01 * p.tau_s / std::sqrt(2.0), 1e-9);
  }
  EXPECT_TRUE(overlapping_allan_deviation(std::vector<double>{1.0, 2.0}, 1.0).empty());
  EXPECT_THROW(overlapping_allan_deviation(ramp, 0.0), UsageError);
  EXPECT_THROW(overlapping_allan_deviation(ramp, 1.0, 0), UsageError);
  EXPECT_THROW(overlapping_allan_deviation(ramp, 1.0, 10, 0.6), UsageError);
}

bool valid_svg_with_data(const std::string& text) {
  const bool starts = text.rfind("<?xml", 0) == 0 || text.rfind("<svg", 0) == 0;
  const bool closes = text.find("</svg>") != std::string::npos;
  const bool data = std::regex_search(text, std::regex(R"(<path[^>]*\sd=['"]M[^'"]{40,})")) ||
                    text.find("<polyline") != std::string::npos;
  return starts && closes && data;
}

class Report : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const std::string t = binary();
    auto simulated = testing::run_in(*dir_, t + " simulate --out chamber.csv --cycles 2 --rate 0.05");
    ASSERT_EQ(simulated.status, 0) << simulated.err;
    result_ = new testing::CommandResult(testing::run_in(
        *dir_, t + " report --data chamber.csv --time time_s --gyro gyro_x,gyro_y,gyro_z --temp temp_x,temp_y,temp_z"
                   " --out out --holdout-fraction 0.5 --evaluations 6"));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete dir_;
  }
  static std::string page() { return testing::read_file(dir_->file("out/report.html")); }
  static nlohmann::json summary() { return nlohmann::json::parse(testing::read_file(dir_->file("out/summary.json"))); }

  static TempDir* dir_;
  static testing::CommandResult* result_;
};
TempDir* Report::dir_ = nullptr;
testing::CommandResult* Report::result_ = nullptr;

// One report run serves the three checks below; CTest runs each TEST in its own
// process, so they are one TEST to run the (slow under the sanitizers) report once.
void runs_and_says_where_the_report_is(const testing::CommandResult* result_) {
  ASSERT_EQ(result_->status, 0) << result_->err;
  EXPECT_NE(result_->out.find("report: out/report.html"), std::string::npos) << result_->out;
  EXPECT_NE(result_->out.find("HELD-OUT"), std::string::npos);
  EXPECT_NE(result_->err.find("fitting svr"), std::string::npos) << "progress lines on stderr";
}

void every_referenced_figure_exists_and_is_svg_with_data(const TempDir* dir_, const std::string& html,
                                                         const nlohmann::json& summary_json) {
  if (!gnuplot_installed()) {
    std::fprintf(stderr, "gnuplot is not installed: figure checks skipped\n");
    return;
  }
  std::set<std::string> referenced;
  const std::regex link(R"(href="([^"]+\.svg)\")");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), link); it != std::sregex_iterator(); ++it) {
    referenced.insert((*it)[1]);
  }
  for (const char* expected : {"raw.svg", "smoothed.svg", "fit_gyro_x.svg", "residual_gyro_z.svg", "cross_axis.svg",
                               "allan.svg"}) {
    EXPECT_TRUE(referenced.count(expected)) << expected << " not on the page";
  }
  for (const auto& file : referenced) {
    const std::string path = dir_->file("out/" + file);
    ASSERT_TRUE(std::filesystem::exists(path)) << file;
    const std::string svg = testing::read_file(path);
    EXPECT_TRUE(valid_svg_with_data(svg)) << file;
    // Labels escaped for gnuplot's enhanced text show the column names as they are.
    EXPECT_EQ(svg.find("gyro\\"), std::string::npos) << file << ": a label shows an escaping backslash";
  }
  EXPECT_NE(testing::read_file(dir_->file("out/raw.svg")).find(">gyro_x<"), std::string::npos) << "raw.svg legend";
  // Inline too: the page opens from disk without its folder.
  std::size_t inline_count = 0;
  for (std::size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) ++inline_count;
  EXPECT_EQ(inline_count, referenced.size());
  const auto listed = summary_json["figures"];
  EXPECT_EQ(listed.size(), referenced.size());
}

void summary_numbers_are_those_on_the_page(const std::string& html, const nlohmann::json& s) {
  ASSERT_TRUE(s["data"]["true_drift_known"].get<bool>()) << "drift_* columns detected";
  std::size_t checked = 0;
  for (const char* part : {"in_sample", "held_out"}) {
    for (const auto& row : s["tables"][part]["rows"]) {
      const auto expect_on_page = [&](double value) {
        EXPECT_NE(html.find(">" + format_number(value) + "<"), std::string::npos) << part << " " << value;
        ++checked;
      };
      expect_on_page(row["original_mse"].get<double>());
      expect_on_page(row["noise_floor"].get<double>());
      for (const auto& cell : row["models"]) {
        expect_on_page(cell["mse"].get<double>());
        expect_on_page(cell["ratio_to_floor"].get<double>());
        expect_on_page(cell["residual_std"].get<double>());
        expect_on_page(cell["residual_peak_to_peak"].get<double>());
      }
    }
  }
  EXPECT_EQ(checked, 2U * 3U * (2U + 3U * 4U));
  // The tuned SVR's blocked CV on the training part, beside what the held-out part gave.
  std::size_t expected = 0;
  for (const auto& row : s["tables"]["held_out"]["rows"]) {
    for (const auto& cell : row["models"]) {
      if (!cell.contains("expected_mse")) continue;
      EXPECT_GT(cell["expected_mse"].get<double>(), 0.0);
      EXPECT_NE(html.find(">" + format_number(cell["expected_mse"].get<double>()) + "<"), std::string::npos);
      ++expected;
    }
  }
  EXPECT_EQ(expected, 3U) << "one per axis: the SVR is tuned by CV, the paper's linear fits are not";
  // Over the training part's floor estimate, as fit prints it; far from the floor, warned.
  for (const auto& row : s["tables"]["held_out"]["rows"]) {
    for (const auto& cell : row["models"]) {
      if (!cell.contains("expected_mse")) continue;
      const double ratio = cell["expected_x_floor_estimate"].get<double>();
      EXPECT_GT(ratio, 2.0) << "the paper's pair on the simulator's unit";
      EXPECT_NE(html.find(">" + format_number(ratio) + "<"), std::string::npos) << ratio;
    }
  }
  EXPECT_NE(html.find("Expected held-out MSE"), std::string::npos);
  for (const auto& c : s["cross_axis"]) {
    EXPECT_NE(html.find(">" + format_number(c["held_out_mse"].get<double>()) + "<"), std::string::npos);
  }
  EXPECT_EQ(s["cross_axis"].size(), 3U);
  EXPECT_EQ(s["split"]["description"], "last 50 % of the log held out");
  EXPECT_NE(html.find("last 50 % of the log held out"), std::string::npos);
  EXPECT_NE(html.find("Which table to believe: the held-out one."), std::string::npos);
}

// The paper's pair leaves hundreds of times the floor on the simulator's unit: one line per
// model, on stderr, in the summary and on the page.
void far_from_the_floor_is_warned(const testing::CommandResult* result_, const std::string& html,
                                  const nlohmann::json& s) {
  const auto& warnings = s.at("warnings");
  ASSERT_EQ(warnings.size(), 3U) << warnings;
  bool linear = false;
  for (const auto& warning : warnings) {
    const auto text = warning.get<std::string>();
    EXPECT_NE(result_->err.find("thermodrift: warning: " + text), std::string::npos) << text;
    EXPECT_NE(html.find(text), std::string::npos) << text;
    linear = linear || text.rfind("linear (dT,rate): gyro_x, gyro_y, gyro_z: on their training data they leave", 0) == 0;
    // report reads one log: the second programme goes to fit
    EXPECT_NE(text.find("another chamber programme in training (fit --data for each)"), std::string::npos) << text;
  }
  EXPECT_TRUE(linear) << warnings;
}

TEST_F(Report, PageFiguresAndSummaryAgree) {
  {
    SCOPED_TRACE("runs and says where the report is");
    runs_and_says_where_the_report_is(result_);
  }
  ASSERT_EQ(result_->status, 0) << result_->err;
  const std::string html = page();
  const auto summary_json = summary();
  {
    SCOPED_TRACE("every referenced figure exists and is SVG with data");
    every_referenced_figure_exists_and_is_svg_with_data(dir_, html, summary_json);
  }
  {
    SCOPED_TRACE("summary numbers are those on the page");
    summary_numbers_are_those_on_the_page(html, summary_json);
  }
  {
    SCOPED_TRACE("far from the floor is warned");
    far_from_the_floor_is_warned(result_, html, summary_json);
  }
}

// With terms beside the paper's pair, the fit and residual figures showed those models
// predicting from the pair's two columns, read past their end (values of 1e187). Each
// model now predicts from its own terms: every value plausible, and the compensated
// rate's Allan deviation defined for every model.
TEST(ReportWithOtherTerms, EveryModelIsDrawnFromItsOwnTerms) {
  TempDir dir;
  const std::string t = binary();
  ASSERT_EQ(testing::run_in(dir, t + " simulate --out chamber.csv --cycles 2 --rate 0.05").status, 0);
  const auto report = testing::run_in(dir, t + " report --data chamber.csv --time time_s --gyro gyro_x,gyro_y,gyro_z"
                                               " --temp temp_x,temp_y,temp_z --out out --holdout-fraction 0.5"
                                               " --evaluations 6 --features lag:600,lagrate:600,dT");
  ASSERT_EQ(report.status, 0) << report.err;
  const auto summary = nlohmann::json::parse(testing::read_file(dir.file("out/summary.json")));
  for (const auto& axis : summary["allan_deviation_held_out"]) {
    ASSERT_EQ(axis["curves"].size(), 7U) << "raw, and three models on each set of terms";
    for (const auto& curve : axis["curves"]) {
      for (const auto& point : curve["tau_s_adev_dph"]) {
        EXPECT_TRUE(point[1].is_number()) << axis["axis"] << " " << curve["label"] << " at " << point[0];
      }
    }
  }
  // The figure's residuals on the held-out rows (every few rows) have about the held-out
  // MSE of the table, model by model.
  if (!gnuplot_installed()) GTEST_SKIP() << "gnuplot is not installed: no figure data to check";
  const double split_hours = summary["split"]["time_s"].get<double>() / 3600.0;
  const auto& models = summary["study"]["models"];
  ASSERT_EQ(models.size(), 6U);
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& row = summary["tables"]["held_out"]["rows"][a];
    const std::string name = row["axis"].get<std::string>();
    const std::string path = dir.file("out/figures/fit_" + name + ".dat");
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    std::vector<double> squares(models.size(), 0.0);
    std::size_t rows = 0;
    for (const auto& line : testing::split_lines(testing::read_file(path))) {
      std::istringstream fields(line);
      std::vector<double> values;
      for (double v; fields >> v;) values.push_back(v);
      if (values.empty() || values[0] < split_hours) continue;
      ASSERT_EQ(values.size(), 2U + 2U * models.size()) << line;  // time, smoothed, then prediction, residual per model
      for (std::size_t m = 0; m < models.size(); ++m) squares[m] += values[3 + 2 * m] * values[3 + 2 * m];
      ++rows;
    }
    ASSERT_GT(rows, 50U) << path;
    for (std::size_t m = 0; m < models.size(); ++m) {
      double table_mse = NAN;
      for (const auto& cell : row["models"]) {
        if (cell["model"] == models[m]["model"] && cell["features"] == models[m]["features"]) {
          table_mse = cell["mse"].get<double>();
        }
      }
      const double figure_mse = squares[m] / static_cast<double>(rows);
      EXPECT_NEAR(figure_mse / table_mse, 1.0, 0.3) << name << ": " << models[m]["model"] << " on "
                                                    << models[m]["features"];
    }
  }
}

TEST(ReportOptions, NeedsAnOutputFolderAndOneLog) {
  TempDir dir;
  dir.write("chamber.csv", "time_s,temp,gyro_x\n0,20,1\n1,20,1\n");
  const auto missing = testing::run_in(dir, binary() + " report --data chamber.csv");
  EXPECT_EQ(missing.status, 2);
}

}  // namespace
}  // namespace thermodrift
