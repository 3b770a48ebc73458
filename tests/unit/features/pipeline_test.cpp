// The feature pipeline: ΔT and rate on known temperature histories, warm-up, gaps,
// decimation, and the pipeline as JSON.
#include "../../support/chamber_logs.hpp"
#include "thermodrift/features/pipeline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

Pipeline ramp_pipeline() {
  Pipeline pipeline;
  pipeline.smooth_seconds = 10;
  pipeline.rate_span_seconds = 20;
  pipeline.gap_seconds = 5;
  pipeline.reference_temperature = 25;
  pipeline.terms = {FeatureTerm{FeatureTerm::Kind::delta_t}, FeatureTerm{FeatureTerm::Kind::rate}};
  return pipeline;
}

using testing::one_axis_log;

TEST(FeatureStream, RateOfALinearRampIsItsSlopeInDegreesPerMinute) {
  const Pipeline pipeline = ramp_pipeline();
  FeatureStream stream(pipeline);
  const double slope = 0.05;  // °C/s = 3 °C/min
  const double dt = 0.5;
  const double start = 1000;
  std::size_t ready = 0;
  for (int k = 0; k < 400; ++k) {
    const double t = start + k * dt;
    const double temperature = 20 + slope * (t - start);
    const auto& sample = stream.push(t, 7.0, temperature);
    if (!sample.ready) continue;
    ++ready;
    ASSERT_EQ(sample.features.size(), 2u);
    EXPECT_NEAR(sample.features[1], 3.0, 1e-9) << "t = " << t;
    // The trailing mean of 20 samples lags the ramp by 19·dt/2 = 4.75 s.
    EXPECT_NEAR(sample.smoothed_temperature, 20 + slope * (t - start - 4.75), 1e-9);
    EXPECT_NEAR(sample.features[0], sample.smoothed_temperature - 25.0, 1e-12);
    EXPECT_NEAR(sample.smoothed_gyro, 7.0, 1e-12);
  }
  EXPECT_EQ(ready, 400u - 60u);  // ready from 30 s = smooth + span on
}

// grad:A-B reads two other channels through their own trailing means and rate spans:
// two ramps of different slopes and offsets give a difference of their trailing means
// (each lags its ramp by the same 4.75 s) and a difference of their slopes.
TEST(FeatureStream, ChannelGradientIsTheDifferenceOfTheSmoothedChannels) {
  Pipeline pipeline = ramp_pipeline();
  pipeline.terms = {FeatureTerm::parse("grad:2-3"), FeatureTerm::parse("gradrate:2-3"), FeatureTerm::parse("dT")};
  EXPECT_EQ(pipeline.channels(), (std::vector<std::size_t>{1, 2}));
  FeatureStream stream(pipeline);
  const double dt = 0.5;
  std::size_t ready = 0;
  for (int k = 0; k < 400; ++k) {
    const double t = k * dt;
    const std::vector<double> channels = {25.0, 10 + 0.05 * t, 12 - 0.02 * t};  // °C/s slopes
    const auto& sample = stream.push(t, 0.0, channels[0], channels);
    if (!sample.ready) continue;
    ++ready;
    const double lagged = t - 4.75;
    EXPECT_NEAR(sample.features[0], (10 + 0.05 * lagged) - (12 - 0.02 * lagged), 1e-9) << "t = " << t;
    EXPECT_NEAR(sample.features[1], (0.05 + 0.02) * 60, 1e-9) << "t = " << t;
    EXPECT_NEAR(sample.features[2], 0.0, 1e-12);
  }
  EXPECT_EQ(ready, 340u);
  // Fewer channels than the terms read: the stream says which.
  FeatureStream short_of_channels(pipeline);
  const std::vector<double> two = {25.0, 10.0};
  EXPECT_THROW(short_of_channels.push(0, 0, 25.0, two), UsageError);
}

TEST(FeatureStream, FallingRampGivesNegativeRate) {
  Pipeline pipeline = ramp_pipeline();
  pipeline.terms = {FeatureTerm{FeatureTerm::Kind::rate}};
  FeatureStream stream(pipeline);
  double last = 0;
  for (int k = 0; k < 200; ++k) {
    const auto& sample = stream.push(k, 0, 60 - 0.02 * k);  // -1.2 °C/min
    if (sample.ready) last = sample.features[0];
  }
  EXPECT_NEAR(last, -1.2, 1e-9);
}

TEST(FeatureStream, ReadyAfterSmoothingPlusRateSpanSeconds) {
  const Pipeline pipeline = ramp_pipeline();  // 10 s + 20 s
  EXPECT_EQ(pipeline.warm_up_seconds(), 30.0);
  FeatureStream stream(pipeline);
  for (int k = 0; k <= 40; ++k) {
    const double t = 500 + k;
    EXPECT_EQ(stream.push(t, 0, 20).ready, k >= 30) << "t - start = " << k;
  }
}

TEST(FeatureStream, GapLongerThanTheThresholdRestartsWarmUp) {
  const Pipeline pipeline = ramp_pipeline();  // gap threshold 5 s
  FeatureStream stream(pipeline);
  for (int k = 0; k <= 40; ++k) stream.push(k, 0, 20);
  // A 4 s step is within the threshold: still ready.
  EXPECT_TRUE(stream.push(44, 0, 20).ready);
  EXPECT_EQ(stream.push(45, 0, 20).since_start, 45.0);
  // A 6 s step is a gap: warm-up again from t = 51, and the old samples are forgotten.
  const auto& after_gap = stream.push(51, 1, 90);
  EXPECT_EQ(after_gap.since_start, 0.0);
  EXPECT_FALSE(after_gap.ready);
  EXPECT_EQ(after_gap.smoothed_temperature, 90.0);
  EXPECT_EQ(after_gap.smoothed_gyro, 1.0);
  for (int t = 52; t < 81; ++t) EXPECT_FALSE(stream.push(t, 1, 90).ready) << t;
  const auto& ready_again = stream.push(81, 1, 90);
  EXPECT_EQ(ready_again.since_start, 30.0);
  EXPECT_TRUE(ready_again.ready);
  EXPECT_NEAR(ready_again.features[1], 0.0, 1e-12);  // no rate across the gap
}

TEST(FeatureStream, DefaultGapIsTheSmoothingWindowAtLeastTenSeconds) {
  Pipeline pipeline;
  pipeline.smooth_seconds = 100;
  EXPECT_EQ(pipeline.effective_gap_seconds(), 100.0);
  pipeline.smooth_seconds = 1;
  EXPECT_EQ(pipeline.effective_gap_seconds(), 10.0);
  pipeline.gap_seconds = 3;
  EXPECT_EQ(pipeline.effective_gap_seconds(), 3.0);
}

TEST(FeatureStream, ResetForgetsHistory) {
  const Pipeline pipeline = ramp_pipeline();
  FeatureStream stream(pipeline);
  for (int k = 0; k <= 40; ++k) stream.push(k, 0, 20);
  stream.reset();
  const auto& sample = stream.push(41, 5, 30);
  EXPECT_FALSE(sample.ready);
  EXPECT_EQ(sample.smoothed_temperature, 30.0);
}

TEST(BuildFeatureTable, KeepsOnlyReadySamplesOfTheChosenAxis) {
  const Pipeline pipeline = ramp_pipeline();
  std::vector<double> time, gyro, temperature;
  for (int k = 0; k < 100; ++k) {
    time.push_back(k);
    gyro.push_back(2.0);
    temperature.push_back(20 + 0.1 * k);
  }
  const FeatureTable table = build_feature_table(pipeline, one_axis_log(time, gyro, temperature), 0, 0, false);
  ASSERT_EQ(table.rows(), 70u);  // t = 30 .. 99
  EXPECT_EQ(table.row.front(), 30u);
  EXPECT_EQ(table.time.front(), 30.0);
  EXPECT_EQ(table.features.rows(), 70);
  EXPECT_EQ(table.features.cols(), 2);
  EXPECT_EQ(table.target.size(), 70);
  for (Eigen::Index i = 0; i < table.features.rows(); ++i) {
    EXPECT_NEAR(table.features(i, 1), 6.0, 1e-9);  // 0.1 °C/s
    EXPECT_NEAR(table.target(i), 2.0, 1e-12);
    EXPECT_NEAR(table.features(i, 0), table.temperature[static_cast<std::size_t>(i)] - 25.0, 1e-12);
  }
}

TEST(BuildFeatureTable, DecimationKeepsEveryKthReadySampleAndRestartsAfterAGap) {
  Pipeline pipeline = ramp_pipeline();
  pipeline.decimation = 3;
  std::vector<double> time, gyro, temperature;
  for (int k = 0; k < 100; ++k) time.push_back(k);
  for (int k = 0; k < 80; ++k) time.push_back(200 + k);  // a gap of 101 s
  for (std::size_t i = 0; i < time.size(); ++i) {
    gyro.push_back(std::sin(time[i]));
    temperature.push_back(20 + 0.01 * time[i] * time[i]);
  }
  const ChamberLog log = one_axis_log(time, gyro, temperature);
  const FeatureTable every = build_feature_table(pipeline, log, 0, 0, false);
  const FeatureTable kept = build_feature_table(pipeline, log, 0, 0, true);
  ASSERT_EQ(every.rows(), 70u + 50u);

  // Every third ready sample of each segment, counted from the segment's first ready one.
  std::vector<std::size_t> expected;
  for (std::size_t i = 0; i < 70; i += 3) expected.push_back(i);
  for (std::size_t i = 0; i < 50; i += 3) expected.push_back(70 + i);
  ASSERT_EQ(kept.rows(), expected.size());
  for (std::size_t j = 0; j < expected.size(); ++j) {
    const auto i = expected[j];
    EXPECT_EQ(kept.row[j], every.row[i]);
    EXPECT_EQ(kept.time[j], every.time[i]);
    EXPECT_EQ(kept.target(static_cast<Eigen::Index>(j)), every.target(static_cast<Eigen::Index>(i)));
    EXPECT_EQ(kept.features.row(static_cast<Eigen::Index>(j)), every.features.row(static_cast<Eigen::Index>(i)));
  }
  EXPECT_EQ(kept.time[0], 30.0);
  EXPECT_EQ(kept.time[24], 230.0);  // the second segment starts over at its first ready sample
}

// The feature searches evaluate thousands of term lists over recorded inputs instead of
// streaming the log again: the columns must be build_feature_table's, bit for bit, through a
// gap, with decimation, for stateful terms and for terms reading other channels.
TEST(RecordedInputs, EvaluateToTheColumnsOfBuildFeatureTable) {
  Pipeline recording = ramp_pipeline();
  recording.decimation = 3;
  recording.terms = {FeatureTerm::parse("dT"), FeatureTerm::parse("grad:2-1"), FeatureTerm::parse("grad:3-1")};
  std::vector<double> time;
  for (int k = 0; k < 300; ++k) time.push_back(0.5 * k);
  for (int k = 0; k < 200; ++k) time.push_back(400 + 0.5 * k);  // a gap: the lags restart
  ChamberLog log = one_axis_log(time, std::vector<double>(time.size(), 0.0), {});
  log.temperature_names = {"a", "b", "c"};
  log.temperature.assign(3, {});
  for (std::size_t i = 0; i < time.size(); ++i) {
    const double t = time[i];
    log.gyro[0][i] = std::sin(0.01 * t);
    log.temperature[0].push_back(20 + 5 * std::sin(0.02 * t));
    log.temperature[1].push_back(21 + 4 * std::sin(0.02 * t - 0.3));
    log.temperature[2].push_back(19 + 0.01 * t);
  }
  const RecordedInputs recorded = record_inputs(recording, log, 0, 0, true);
  EXPECT_EQ(recorded.channels, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(recorded.rows(), time.size());

  Pipeline asked = recording;
  asked.terms.clear();
  for (const char* name : {"lag:30", "lagrate:30", "hinge:30:1.5", "lag2:20:10", "nodehinge:20:10:0:-1", "play:30:0.5",
                           "dir:40:30", "gradrate:30:15", "lag:30*lagrate:30", "rate^2", "grad:3-2", "gradrate:2-1"}) {
    asked.terms.push_back(FeatureTerm::parse(name));
  }
  const FeatureTable streamed = build_feature_table(asked, log, 0, 0, true);
  const Eigen::MatrixXd columns = evaluate_terms(asked.terms, recorded);
  ASSERT_EQ(recorded.kept, streamed.row);
  ASSERT_EQ(columns.rows(), streamed.features.rows());
  ASSERT_EQ(columns.cols(), streamed.features.cols());
  EXPECT_TRUE((columns.array() == streamed.features.array()).all());

  // A channel the recording did not smooth is refused, not read as zero.
  Pipeline own_only = recording;
  own_only.terms = {FeatureTerm::parse("dT"), FeatureTerm::parse("grad:2-1")};
  EXPECT_THROW(evaluate_terms({FeatureTerm::parse("grad:3-1")}, record_inputs(own_only, log, 0, 0, true)), UsageError);
}

// The feature searches score sets on the decimated rows alone (sparse_inputs, the filters
// fed a straight line between them). Over a log of smooth temperatures with a gap, the
// sparse rows keep every kept row and every restart, no more than `every` rows apart, and
// their columns are the whole log's to within a small part of each column's range; the
// stateless terms exactly.
TEST(RecordedInputs, SparseRowsGiveTheColumnsOfEveryRow) {
  Pipeline recording = ramp_pipeline();
  recording.decimation = 10;
  recording.terms = {FeatureTerm::parse("dT"), FeatureTerm::parse("grad:2-1")};
  std::vector<double> time;
  for (int k = 0; k < 4000; ++k) time.push_back(k);
  for (int k = 0; k < 3000; ++k) time.push_back(4100 + k);  // a gap: the lags restart
  ChamberLog log = one_axis_log(time, std::vector<double>(time.size(), 0.0), {});
  log.temperature_names = {"a", "b"};
  log.temperature.assign(2, {});
  for (const double t : time) {
    log.temperature[0].push_back(20 + 30 * std::sin(2 * M_PI * t / 5000));
    log.temperature[1].push_back(20 + 28 * std::sin(2 * M_PI * t / 5000 - 0.1));
  }
  const RecordedInputs every_row = record_inputs(recording, log, 0, 0, true);
  const RecordedInputs sparse = sparse_inputs(every_row, 10);
  ASSERT_EQ(sparse.kept.size(), every_row.kept.size());
  EXPECT_EQ(sparse.target, every_row.target);
  EXPECT_LT(sparse.rows(), every_row.rows() / 9);
  double elapsed = 0, longest = 0;
  std::size_t restarts = 0;
  for (std::size_t i = 0; i < sparse.rows(); ++i) {
    restarts += sparse.step_seconds[i] > 0 ? 0 : 1;
    elapsed += sparse.step_seconds[i];
    longest = std::max(longest, sparse.step_seconds[i]);
  }
  EXPECT_EQ(restarts, 2u);
  EXPECT_EQ(longest, 10.0);
  EXPECT_GE(elapsed, 3999.0 + 2999.0 - 2 * 10);  // up to the last kept row of each run
  EXPECT_EQ(sparse.dense_step_seconds, 1.0);

  std::vector<FeatureTerm> terms;
  for (const char* name : {"dT", "rate", "grad:2-1", "lag:30", "lagrate:30", "hinge:600:1.5", "lag2:400:100",
                           "nodehinge:400:100:0:-1", "nodehinge:30:0:60:2", "play:300:0.5", "dir:400:300",
                           "gradrate:300:60", "on:300"}) {
    terms.push_back(FeatureTerm::parse(name));
  }
  const Eigen::MatrixXd exact = evaluate_terms(terms, every_row);
  const Eigen::MatrixXd close = evaluate_terms(terms, sparse);
  ASSERT_EQ(close.rows(), exact.rows());
  for (Eigen::Index j = 0; j < exact.cols(); ++j) {
    const double range = exact.col(j).maxCoeff() - exact.col(j).minCoeff();
    ASSERT_GT(range, 0) << terms[static_cast<std::size_t>(j)].name();
    EXPECT_LT((close.col(j) - exact.col(j)).cwiseAbs().maxCoeff(), (j < 3 ? 0.0 : 1e-3) * range + 1e-300)
        << terms[static_cast<std::size_t>(j)].name();
  }
}

TEST(BuildFeatureTable, AppendRowsConcatenates) {
  const Pipeline pipeline = ramp_pipeline();
  std::vector<double> time, gyro, temperature;
  for (int k = 0; k < 50; ++k) {
    time.push_back(k);
    gyro.push_back(k);
    temperature.push_back(20);
  }
  const ChamberLog log = one_axis_log(time, gyro, temperature);
  FeatureTable table;
  append_rows(table, build_feature_table(pipeline, log, 0, 0, false));
  append_rows(table, build_feature_table(pipeline, log, 0, 0, false));
  ASSERT_EQ(table.rows(), 40u);
  EXPECT_EQ(table.features.rows(), 40);
  EXPECT_EQ(table.target(20), table.target(0));
  EXPECT_EQ(table.time[20], 30.0);
  EXPECT_EQ(table.run_start, (std::vector<std::size_t>{0, 20}));  // each appended log is a run
}

TEST(DefaultDecimation, AboutTenSamplesPerWindow) {
  EXPECT_EQ(default_decimation(100, 1), 10u);
  EXPECT_EQ(default_decimation(100, 0.02), 500u);
  EXPECT_EQ(default_decimation(1, 1), 1u);
  EXPECT_EQ(default_decimation(100, 0), 1u);
}

TEST(PipelineJson, RoundTripsEveryField) {
  Pipeline pipeline;
  pipeline.smooth_seconds = 37.5;
  pipeline.rate_span_seconds = 12.25;
  pipeline.gap_seconds = 80;
  pipeline.decimation = 4;
  pipeline.reference_temperature = 21.123456789012345;
  pipeline.terms = {FeatureTerm{FeatureTerm::Kind::rate}, FeatureTerm{FeatureTerm::Kind::delta_t}};
  const nlohmann::json json = pipeline.to_json();
  const Pipeline back = Pipeline::from_json(nlohmann::json::parse(json.dump()));
  EXPECT_EQ(back.smooth_seconds, pipeline.smooth_seconds);
  EXPECT_EQ(back.rate_span_seconds, pipeline.rate_span_seconds);
  EXPECT_EQ(back.gap_seconds, pipeline.gap_seconds);
  EXPECT_EQ(back.decimation, pipeline.decimation);
  EXPECT_EQ(back.reference_temperature, pipeline.reference_temperature);
  EXPECT_EQ(back.term_names(), (std::vector<std::string>{"rate", "dT"}));
  EXPECT_FALSE(back.libsvm);
  EXPECT_EQ(back.to_json(), json);
}

TEST(PipelineJson, DefaultGapIsStoredAsItsEffectiveValue) {
  Pipeline pipeline;  // gap 0: the smoothing window
  const Pipeline back = Pipeline::from_json(pipeline.to_json());
  EXPECT_EQ(back.effective_gap_seconds(), pipeline.effective_gap_seconds());
}

TEST(PipelineJson, LibsvmPipelineRoundTrips) {
  const Pipeline pipeline = Pipeline::libsvm_input(3);
  const Pipeline back = Pipeline::from_json(pipeline.to_json());
  EXPECT_TRUE(back.libsvm);
  EXPECT_EQ(back.term_names(), (std::vector<std::string>{"x1", "x2", "x3"}));
}

TEST(PipelineJson, RejectsWhatDoesNotFit) {
  const nlohmann::json good = Pipeline{}.to_json();
  auto with = [&](const char* key, nlohmann::json value) {
    nlohmann::json json = good;
    json[key] = std::move(value);
    return json;
  };
  EXPECT_THROW(Pipeline::from_json(with("version", 2)), Error);
  EXPECT_THROW(Pipeline::from_json(with("window", "centered")), Error);
  EXPECT_THROW(Pipeline::from_json(with("terms", {"dT", "humidity"})), UsageError);
  EXPECT_THROW(Pipeline::from_json(with("terms", nlohmann::json::array())), UsageError);
  EXPECT_THROW(Pipeline::from_json(with("smooth_seconds", -1)), UsageError);
  EXPECT_THROW(Pipeline::from_json(with("rate_span_seconds", 0)), UsageError);
  EXPECT_THROW(Pipeline::from_json(with("decimation", 0)), UsageError);
  nlohmann::json missing = good;
  missing.erase("reference_temperature");
  EXPECT_ANY_THROW(Pipeline::from_json(missing));
}

TEST(FeatureTerm, ParsesKnownNames) {
  EXPECT_TRUE(FeatureTerm::parse("dT").is_atom(FeatureTerm::Kind::delta_t));
  EXPECT_TRUE(FeatureTerm::parse("rate").is_atom(FeatureTerm::Kind::rate));
  EXPECT_EQ(FeatureTerm::parse("x3").factors.at(0).atom.input_index, 2u);
  EXPECT_THROW(FeatureTerm::parse("x0"), UsageError);
  EXPECT_THROW(FeatureTerm::parse("dt"), UsageError);
}

}  // namespace
}  // namespace thermodrift
