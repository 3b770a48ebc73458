// The feature pipeline: how a log becomes (features, target) for one gyro axis. It is a
// value stored in the model file, and the one streaming implementation below serves
// fitting, evaluation and compensation alike, so they can never disagree.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "thermodrift/features/moving_average.hpp"
#include "thermodrift/features/terms.hpp"
#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift {

// Feature terms a chamber-log pipeline may have. The identification's largest sets hold
// about 60; a linear model's prediction costs terms × regressors per sample, so a file of
// 5,000 terms took minutes to evaluate. libsvm-format models have one term per column,
// up to kMaxLibsvmFeatureIndex.
inline constexpr std::size_t kMaxPipelineTerms = 256;

struct Pipeline {
  static constexpr int kVersion = 1;
  double smooth_seconds = 100;      // trailing moving-average window on gyro and temperature (the paper: 100 s)
  double rate_span_seconds = 100;   // span of the backward difference giving dT/dt
  double gap_seconds = 0;           // a time step longer than this restarts the warm-up; 0: smooth_seconds (at least 10 s)
  std::size_t decimation = 1;       // fitting keeps every k-th ready sample (neighbours of a 100 s mean are near copies)
  double reference_temperature = 0; // ΔT = T_s - reference, °C; set from the training log
  // The temperature channel ΔT, its rate and every lag of it are computed from (0-based,
  // in the model's temperature inputs: one per axis, then the extra ones): absent, the
  // axis' own. Another axis' thermometer can sit on this axis' coil, closer to it than
  // its own (docs/features.md, "The node's thermometer").
  std::optional<std::size_t> temperature_channel;
  std::vector<FeatureTerm> terms{FeatureTerm{FeatureTerm::Kind::delta_t},
                                 FeatureTerm{FeatureTerm::Kind::rate}};

  bool libsvm = false;              // features are libsvm-format columns as given: no smoothing, no log

  // The pipeline of a model fitted on libsvm-format data with `columns` features.
  static Pipeline libsvm_input(std::size_t columns);

  // Seconds of history a sample needs before its features are ready.
  double warm_up_seconds() const { return smooth_seconds + rate_span_seconds; }
  double effective_gap_seconds() const;
  std::vector<std::string> term_names() const;
  // The temperature channels (0-based, sorted, distinct) its grad terms read.
  std::vector<std::size_t> channels() const;
  // The channel ΔT is computed from, for an axis whose own channel is `own`.
  std::size_t temperature_input(std::size_t own) const { return temperature_channel.value_or(own); }
  // How long its slowest state remembers where it started, s: over its terms' atoms, the
  // largest time constant plus the one in series behind it (a chain's mean delay); 0
  // for the paper's pair.
  double longest_delay() const;
  void validate() const;  // UsageError on nonsense (negative window, no terms, ...)

  nlohmann::json to_json() const;
  static Pipeline from_json(const nlohmann::json& json);  // throws Error on a bad value
};

// Decimation giving about ten samples per smoothing window: neighbours of a 100 s mean
// carry almost no new information, and SVR cost grows with n².
std::size_t default_decimation(double smooth_seconds, double sample_interval_seconds);

// One temperature channel through the pipeline: its trailing mean over the smoothing
// window and the backward difference of that mean over the rate span (to the last mean
// at or before t - span, so the difference spans at least the span).
class SmoothedChannel {
 public:
  SmoothedChannel(double smooth_seconds, double rate_span_seconds);
  struct Value {
    double mean = 0;  // °C
    double rate = 0;  // °C/min
  };
  Value push(double time, double temperature);
  void reset();

 private:
  struct Stamped {
    double time;
    double value;
  };
  TrailingMean mean_;
  double span_;
  std::vector<Stamped> history_;  // the mean over the last rate span
  std::size_t history_head_ = 0;
};

// Streaming state of the pipeline for one axis: push one sample, read its features.
class FeatureStream {
 public:
  explicit FeatureStream(const Pipeline& pipeline);

  struct Sample {
    bool ready = false;           // false during warm-up (after the start or a gap)
    double since_start = 0;       // s since the stream (re)started: lags settle over this
    double step_seconds = 0;      // s since the previous sample; 0 at a (re)start
    double smoothed_gyro = 0;     // °/h, the drift target
    // s: half the time the smoothing window's samples span, (newest - oldest) / 2. The
    // window's mean of an evenly sampled signal is its value this long before the newest
    // sample (to first order): the smoothed drift a model predicts lags the drift by it.
    double window_lag = 0;
    double smoothed_temperature = 0;  // °C
    double smoothed_rate = 0;         // its dT/dt over the rate span, °C/min
    std::span<const double> features;  // one value per pipeline term
  };

  // `time` must increase; `temperature` is the axis's temperature channel; `channels`,
  // every temperature channel in order, is read only by grad terms (UsageError when one
  // they read is missing).
  const Sample& push(double time, double gyro, double temperature, std::span<const double> channels = {});
  void reset();
  // What the terms read at the last push (channel values: the channels the terms read).
  const TermInputs& inputs() const { return inputs_; }

 private:
  const Pipeline* pipeline_;
  TrailingMean gyro_mean_;
  SmoothedChannel temperature_;
  std::vector<std::size_t> channels_;            // read by grad terms, 0-based
  std::vector<SmoothedChannel> channel_filters_;  // one per entry of channels_
  std::vector<double> channel_means_;            // indexed by channel number
  std::vector<double> channel_rates_;
  bool started_ = false;
  double start_time_ = 0;
  double last_time_ = 0;
  TermEvaluator terms_;
  std::vector<double> features_;
  TermInputs inputs_;
  Sample sample_;
};

// Features and target of the ready samples of one axis.
struct FeatureTable {
  Eigen::MatrixXd features;       // one row per sample, one column per term
  Eigen::VectorXd target;         // smoothed gyro, °/h
  std::vector<double> time;       // s
  std::vector<double> since_start;  // s since the pipeline (re)started: the log's start or a gap
  std::vector<double> temperature;  // smoothed, °C
  std::vector<double> rate;         // smoothed dT/dt, °C/min
  std::vector<std::size_t> row;   // index of the log row
  // First row of each run: one per log appended (a table of one log holds {0}). Runs are
  // separate chamber runs: cross-validation can hold out whole runs.
  std::vector<std::size_t> run_start;
  std::size_t rows() const { return row.size(); }
};

// Runs the pipeline over one axis of a log. `decimate` applies pipeline.decimation.
FeatureTable build_feature_table(const Pipeline& pipeline, const ChamberLog& log,
                                 std::size_t gyro_axis, std::size_t temperature_channel,
                                 bool decimate);

// The terms' inputs at every row of one axis of a log (ΔT, rate, step, the channels that
// `pipeline`'s terms read), smoothed once, and the rows a table of `pipeline` keeps: any
// list of terms on the same node channel and channels evaluates over it to the columns
// build_feature_table would give, bit for bit, without smoothing the log again (the
// feature searches evaluate thousands of lists over one log).
struct RecordedInputs {
  std::vector<double> delta_t, rate, step_seconds;
  std::vector<std::size_t> channels;       // recorded channels, 0-based, as Pipeline::channels()
  std::vector<double> channel_means, channel_rates;  // row-major, width() per row
  std::vector<std::size_t> kept;           // rows a (decimated) table keeps
  std::vector<double> target;              // the smoothed gyro at the kept rows: the table's target
  // sparse_inputs: the median step of the rows it came from (0: every row is here); the
  // terms are then evaluated with the linear hold, half that step ahead.
  double dense_step_seconds = 0;
  std::size_t rows() const { return delta_t.size(); }
  // Channel numbers per row: the highest recorded channel + 1.
  std::size_t width() const { return channels.empty() ? 0 : channels.back() + 1; }
};
RecordedInputs record_inputs(const Pipeline& pipeline, const ChamberLog& log, std::size_t gyro_axis,
                             std::size_t temperature_channel, bool decimate);
// One column per term, one row per kept row. A term reading a channel not recorded is a
// UsageError.
Eigen::MatrixXd evaluate_terms(const std::vector<FeatureTerm>& terms, const RecordedInputs& inputs);
// The rows of `inputs` the terms need, at most `every` rows apart: every kept row, every
// restart (step 0) and enough rows between them, each with the time since the one before.
// Its columns are those of the whole log to within how far the smoothed inputs bend over
// `every` rows, for about 1/`every` of the work.
RecordedInputs sparse_inputs(const RecordedInputs& inputs, std::size_t every);

// Appends the rows of `more` to `table` (several logs fitted together), with its runs.
void append_rows(FeatureTable& table, const FeatureTable& more);

}  // namespace thermodrift
