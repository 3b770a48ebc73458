// The paper's cross-axis experiment (its Fig. 3): one SVR trained on the pooled samples of
// every axis but one, tested on the axis left out. It tells whether the axes share one
// drift law; in the paper, and usually, they do not.
#pragma once

#include <string>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/metrics.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {

struct CrossAxisResult {
  std::size_t left_out = 0;               // axis index tested on
  std::string left_out_name;
  std::vector<std::string> training_axes;  // the axes pooled for training
  AxisModel model;                        // the pooled SVR, reading the left-out axis's features
  std::size_t training_samples = 0;
  ResidualMetrics held_out;               // on the left-out axis, held-out part of the log
  ResidualMetrics whole_log;              // on the left-out axis, whole log
  double seconds = 0;
};

// For each axis a: pools the decimated feature tables of the other axes over
// `training` (each built with that axis's own pipeline from `fitted`), fits an SVR with
// the options and hyper-parameters the self-regression SVR of axis a used, and evaluates
// it on axis a of `held_out` and of `whole`. `fitted` must be an SVR calibration of the
// same axes. Needs at least two axes (else returns nothing).
std::vector<CrossAxisResult> run_cross_axis(const ChamberLog& training, const ChamberLog& held_out,
                                            const ChamberLog& whole, const DriftModel& fitted,
                                            const CalibrationOptions& options);

}  // namespace thermodrift
