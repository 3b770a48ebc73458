// The report of the paper's study on one log: the study (report/study.hpp), the
// cross-axis experiment, compensation of every axis, Allan deviation before and after,
// gnuplot SVG figures, DIR/report.html (one self-contained page) and DIR/summary.json
// (the same numbers). docs/report.md describes what is in it and why.
//
//   ReportOptions options;
//   options.out_dir = "report";
//   options.study.split_row = first_row_of_last_cycle;
//   ReportResult result = write_report(log, spec, options);   // result.html_path
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/report/study.hpp"

namespace thermodrift {

struct ReportOptions {
  // Models, calibration settings, split, progress; study.calibration.stop also stops the
  // report's own steps (the cross-axis fits, compensation, figures, gnuplot).
  StudyOptions study;
  // Created if missing (its parents too). Written whole or not at all: into a staging
  // folder beside it, committed at the end (io/atomic_file.hpp, StagedFolder), so an error
  // or a stop leaves it as it was; an existing folder keeps the files the report does not
  // write and gets the others replaced.
  std::string out_dir;
  std::string title = "thermodrift report";
  std::string command_line;                // how the report was asked for (shown on the page)
  // True drift per axis and log row (°/h), when known (simulated data): gives the noise
  // floor and each result's ratio to it. Empty: unknown.
  std::vector<std::vector<double>> true_drift;
  std::string gnuplot = "gnuplot";         // program drawing the figures; absent: a page without figures
  std::vector<std::pair<std::string, double>> earlier_steps;  // (step, seconds) done by the caller
  std::uint64_t seed = 1;                  // recorded with the parameters
  int threads = 1;                         // recorded with the parameters
  std::function<void(const std::string&)> progress;  // one line per step; may be empty
};

struct ReportResult {
  Study study;
  nlohmann::json summary;       // what summary.json holds
  std::string html_path;
  std::string summary_path;
  bool figures_drawn = false;
  std::string figures_note;     // why there are no figures, when there are none
};

// The paper's study as `thermodrift report` and `demo` run it: linear, stepwise and
// SVR + AFSA (C and σ tuned per axis by blocked 5-fold CV on the training part, with
// `evaluations` per axis), on the paper's pair and, when given, on `other_terms` ({"auto"}:
// identified by `identify`); `threads` for the tuning, the SVR fits and the feature
// search, every random choice from `seed`, stopped by `stop`. The caller adds out_dir,
// the split, the title and what it knows of the data.
ReportOptions paper_report_options(std::uint64_t seed, int threads, long evaluations,
                                   FeatureSelectionOptions::Method identify,
                                   std::vector<std::string> other_terms, StopToken stop);

// Runs everything and writes DIR/report.html, DIR/summary.json, DIR/*.svg, the gnuplot
// script and its data (DIR/figures/), and one model file per model kind. Throws the
// study's errors; a failing gnuplot is an Error naming its log file.
ReportResult write_report(const ChamberLog& log, const LogSpec& spec, const ReportOptions& options);

// How the page prints every number (4 significant digits); tests compare with it.
std::string format_number(double value);

// A partially linear SVR's kernel check (fit.kernel_check's JSON) in words: "kept: ..." or
// "left out: ...", with both nested CV MSEs.
std::string kernel_check_text(const nlohmann::json& check);

}  // namespace thermodrift
