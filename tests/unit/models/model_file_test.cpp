// The model file: saved and loaded unchanged, and every file that does not fit rejected
// with a one-line DataError (truncation with the line and column where the text ends).
#include "thermodrift/models/model_file.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <tuple>

#include "../../support/temp_dir.hpp"
#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

using testing::TempDir;

using testing::contains;

DriftModel two_axis_model() {
  DriftModel model;
  model.gyro_unit = GyroUnit::dps;
  model.rate_hz = 50;
  for (int a = 0; a < 2; ++a) {
    AxisModel axis;
    axis.name = a == 0 ? "gyro_x" : "gyro_y";
    axis.gyro_column = std::to_string(5 + a);
    axis.temperature_column = "1";
    axis.pipeline.smooth_seconds = 1;
    axis.pipeline.rate_span_seconds = 1;
    axis.pipeline.decimation = 5;
    axis.pipeline.reference_temperature = 31.0625 + a;
    axis.kind = a == 0 ? ModelKind::linear : ModelKind::stepwise;
    LinearModel linear;
    linear.regressors = a == 0 ? linear_regressors(2) : quadratic_regressors(2);
    linear.coefficients = Eigen::VectorXd::LinSpaced(static_cast<Eigen::Index>(linear.regressors.size()), -1.5, 2.25);
    linear.intercept = 0.1 + a;
    axis.model = linear;
    axis.fit.terms = axis.pipeline.term_names();
    axis.fit.training_samples = 1000 + a;
    model.axes.push_back(axis);
  }
  return model;
}

DataError load_error(const std::string& path) {
  try {
    load_drift_model(path);
  } catch (const DataError& error) {
    return error;
  }
  ADD_FAILURE() << "no DataError loading " << path;
  return DataError("", 0, 0, "");
}

// The 1-based line and column of the `occurrence`-th `needle` in `text` (0: the first),
// plus `offset` characters.
std::pair<std::size_t, std::size_t> position_in(const std::string& text, const std::string& needle,
                                                std::size_t offset = 0, int occurrence = 0) {
  std::size_t at = text.find(needle);
  for (int i = 0; i < occurrence && at != std::string::npos; ++i) at = text.find(needle, at + 1);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no " << needle;
    return {0, 0};
  }
  at += offset;
  const auto line_start = text.rfind('\n', at);
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  return {line, line_start == std::string::npos ? at + 1 : at - line_start};
}

// The saved JSON of the two-axis model, for editing.
nlohmann::json saved_json(const TempDir& dir) {
  const auto path = dir.file("model.json");
  save_drift_model(two_axis_model(), path);
  return nlohmann::json::parse(testing::read_file(path));
}

// A one-vector SVR on (dT, rate) whose file every check accepts, and what loading a
// changed copy of it says ("accepted" when nothing).
const std::vector<std::string> kSvrTerms = {"dT", "rate"};

SvrModel small_svr() {
  SvrModel svr;
  svr.scaling = Standardization::identity(2);
  svr.function.gamma = 0.5;
  svr.function.coefficients = Eigen::VectorXd::Constant(1, 0.3);
  svr.function.support_vectors = Eigen::MatrixXd::Constant(1, 2, 0.2);
  svr.C = 10;
  return svr;
}

std::string refusal(const nlohmann::json& body) {
  try {
    SvrModel::from_json(body, kSvrTerms);
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

TEST(ModelFile, SaveAndLoadGiveTheSameModel) {
  TempDir dir;
  const auto path = dir.file("model.json");
  const DriftModel model = two_axis_model();
  save_drift_model(model, path);
  const DriftModel back = load_drift_model(path);
  EXPECT_EQ(back.gyro_unit, GyroUnit::dps);
  EXPECT_FALSE(back.time_column);
  ASSERT_TRUE(back.rate_hz);
  EXPECT_EQ(*back.rate_hz, 50.0);
  ASSERT_EQ(back.axes.size(), 2u);
  for (std::size_t a = 0; a < 2; ++a) {
    const auto& want = model.axes[a];
    const auto& got = back.axes[a];
    EXPECT_EQ(got.name, want.name);
    EXPECT_EQ(got.gyro_column, want.gyro_column);
    EXPECT_EQ(got.temperature_column, want.temperature_column);
    EXPECT_EQ(got.kind, want.kind);
    EXPECT_EQ(got.pipeline.to_json(), want.pipeline.to_json());
    const auto& linear_want = std::get<LinearModel>(want.model);
    const auto& linear_got = std::get<LinearModel>(got.model);
    EXPECT_EQ(linear_got.intercept, linear_want.intercept);
    EXPECT_EQ(linear_got.coefficients, linear_want.coefficients);
    EXPECT_EQ(fit_record_to_json(got.fit), fit_record_to_json(want.fit));
    const std::vector<double> features = {2.5, -0.75};
    EXPECT_EQ(got.predict(features), want.predict(features));
  }
  // Saving what was loaded gives the same bytes.
  const auto again = dir.file("again.json");
  save_drift_model(back, again);
  EXPECT_EQ(testing::read_file(again), testing::read_file(path));
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"again.json", "model.json"}));  // no temporary left
}

TrainingEnvelope heating_only_envelope() {
  TrainingEnvelope envelope;
  envelope.temperature = {19.5, 59.875};
  envelope.rate = {-0.0625, 1.125};
  envelope.heating_seen = true;
  envelope.cooling_seen = false;
  envelope.terms = {{-20.25, 20.125}, {-0.0625, 1.125}};
  return envelope;
}

// The training envelope is kept exactly; a file without one (written before it was
// recorded) still loads, and a present one is checked.
// The linear part of a partially linear SVR is saved with it and predicts again after a
// load; a file without one is a plain SVR.
TEST(ModelFile, PartiallyLinearSvrRoundTrips) {
  const std::vector<std::string> terms = {"lag:300", "rate"};
  SvrModel svr = small_svr();
  svr.function.bias = 0.1;
  LinearModel linear;
  linear.intercept = 1.5;
  linear.regressors = linear_regressors(2);
  linear.coefficients = Eigen::Vector2d(0.02, -0.7);
  svr.linear_part = linear;
  const SvrModel back = SvrModel::from_json(svr.to_json(terms), terms);
  ASSERT_TRUE(back.linear_part.has_value());
  const std::vector<double> x = {12.0, 0.8};
  EXPECT_DOUBLE_EQ(back.predict(x), svr.predict(x));
  SvrModel plain = svr;
  plain.linear_part.reset();
  EXPECT_NEAR(svr.predict(x) - plain.predict(x), 1.5 + 0.02 * 12 - 0.7 * 0.8, 1e-12);
  EXPECT_FALSE(SvrModel::from_json(plain.to_json(terms), terms).linear_part.has_value());
}

TEST(ModelFile, TrainingEnvelopeRoundTripsAndIsOptional) {
  TempDir dir;
  DriftModel model = two_axis_model();
  model.axes[0].envelope = heating_only_envelope();
  const auto path = dir.file("model.json");
  save_drift_model(model, path);
  const DriftModel back = load_drift_model(path);
  ASSERT_TRUE(back.axes[0].envelope);
  EXPECT_EQ(back.axes[0].envelope->temperature, (Range{19.5, 59.875}));
  EXPECT_EQ(back.axes[0].envelope->rate, (Range{-0.0625, 1.125}));
  EXPECT_TRUE(back.axes[0].envelope->heating_seen);
  EXPECT_FALSE(back.axes[0].envelope->cooling_seen);
  EXPECT_EQ(back.axes[0].envelope->terms, heating_only_envelope().terms);
  EXPECT_FALSE(back.axes[1].envelope);  // the older form, without the field

  auto json = nlohmann::json::parse(testing::read_file(path));
  ASSERT_TRUE(json["axes"][0].contains("training_envelope"));
  EXPECT_FALSE(json["axes"][1].contains("training_envelope"));
  const std::vector<std::pair<std::string, nlohmann::json>> bad = {
      {"min > max", {{"temperature_c", {60.0, 20.0}}}},
      {"not finite", {{"rate_c_per_min", {-1.0, std::numeric_limits<double>::infinity()}}}},
      {"term ranges for 2 terms", {{"terms", {{0.0, 1.0}}}}},
  };
  for (const auto& [what, patch] : bad) {
    auto edited = json;
    edited["axes"][0]["training_envelope"].merge_patch(patch);
    dir.write("bad.json", edited.dump());
    const DataError error = load_error(dir.file("bad.json"));
    EXPECT_TRUE(contains(error.what(), what)) << error.what();
    EXPECT_TRUE(contains(error.what(), "axis 1")) << error.what();
  }
}

TEST(ModelFile, DespikeRoundTripsIntoTheLogSpecAndIsChecked) {
  TempDir dir;
  DriftModel model = two_axis_model();
  EXPECT_FALSE(model.log_spec().despike);
  model.despike = DespikeOptions{25, 5};
  model.despiked_gyro = {3, 0};
  model.despiked_temperature = {1};
  const auto path = dir.file("model.json");
  save_drift_model(model, path);
  const DriftModel back = load_drift_model(path);
  ASSERT_TRUE(back.log_spec().despike);
  EXPECT_EQ(back.log_spec().despike->window, 25u);
  EXPECT_EQ(back.log_spec().despike->sigmas, 5.0);
  EXPECT_EQ(back.despiked_gyro, (std::vector<std::size_t>{3, 0}));
  EXPECT_EQ(back.despiked_temperature, (std::vector<std::size_t>{1}));

  const auto json = nlohmann::json::parse(testing::read_file(path));
  const std::vector<std::pair<std::string, nlohmann::json>> bad = {
      {"despike window must be an integer", {{"window", -1}}},
      {"despike window must be 3 to 100000", {{"window", 2}}},
      {"despike sigmas must be a number", {{"sigmas", "six"}}},
      {"despike threshold must be a positive", {{"sigmas", 0}}},
      {"must hold \"window\" and \"sigmas\"", {{"window", nullptr}}},
      // Long fuzzing found a negative count converted to an unsigned (undefined behaviour).
      {"despike replaced_in_training temperature must be an integer from 0",
       {{"replaced_in_training", {{"temperature", {10, -5.818583831893798}}}}}},
      {"despike replaced_in_training gyro must be an integer from 0", {{"replaced_in_training", {{"gyro", {1.5}}}}}},
      {"despike replaced_in_training gyro must be a list", {{"replaced_in_training", {{"gyro", 3}}}}},
      {"\"replaced_in_training\" must be an object", {{"replaced_in_training", {1, 2}}}},
  };
  for (const auto& [what, patch] : bad) {
    auto edited = json;
    edited["despike"].merge_patch(patch);
    dir.write("bad.json", edited.dump());
    const DataError error = load_error(dir.file("bad.json"));
    EXPECT_TRUE(contains(error.what(), what)) << error.what();
  }
}

TEST(ModelFile, LogSpecReadsLikeTheTrainingLog) {
  const LogSpec spec = two_axis_model().log_spec();
  EXPECT_EQ(spec.gyro_columns, (std::vector<std::string>{"5", "6"}));
  EXPECT_EQ(spec.temperature_columns, (std::vector<std::string>{"1", "1"}));
  EXPECT_EQ(spec.gyro_unit, GyroUnit::dps);
  EXPECT_EQ(spec.rate_hz, 50.0);
}

// A model with grad terms reads its extra temperature columns after the axes' own, and
// a grad term reading past them is refused on load.
TEST(ModelFile, ExtraTemperatureColumnsRoundTripAndBoundGradTerms) {
  TempDir dir;
  DriftModel model = two_axis_model();
  model.axes[1].pipeline.terms.push_back(FeatureTerm::parse("grad:2-3"));
  auto& linear = std::get<LinearModel>(model.axes[1].model);
  linear.regressors = linear_regressors(3);
  linear.coefficients = Eigen::Vector3d(0.5, -0.25, 2.0);
  model.extra_temperature_columns = {"temp_chamber"};
  EXPECT_EQ(model.temperature_inputs(), 3u);
  const auto path = dir.file("model.json");
  save_drift_model(model, path);
  const DriftModel back = load_drift_model(path);
  EXPECT_EQ(back.extra_temperature_columns, (std::vector<std::string>{"temp_chamber"}));
  EXPECT_EQ(back.log_spec().temperature_columns, (std::vector<std::string>{"1", "1", "temp_chamber"}));
  EXPECT_EQ(back.axes[1].pipeline.channels(), (std::vector<std::size_t>{1, 2}));

  auto json = nlohmann::json::parse(testing::read_file(path));
  json.erase("extra_temperature_columns");
  dir.write("short.json", json.dump());
  const DataError error = load_error(dir.file("short.json"));
  EXPECT_TRUE(contains(error.what(), "temperature channel 3")) << error.what();
}

TEST(ModelFile, SavingOverAnInputIsRefused) {
  TempDir dir;
  const auto data = dir.write("data.csv", "time_s,gyro,temp\n0,1,2\n");
  EXPECT_THROW(save_drift_model(two_axis_model(), data, {data}), UsageError);
  EXPECT_EQ(testing::read_file(data), "time_s,gyro,temp\n0,1,2\n");
}

TEST(ModelFileErrors, AnotherVersion) {
  TempDir dir;
  auto json = saved_json(dir);
  json["version"] = 2;
  const auto path = dir.write("v2.json", json.dump(1));
  const auto error = load_error(path);
  EXPECT_EQ(error.file(), path);
  EXPECT_EQ(std::pair(error.line(), error.column()), position_in(json.dump(1), "\"version\": 2", 11));
  EXPECT_TRUE(contains(error.message(), "model file version 2 is not supported (this build reads version 1)"))
      << error.what();
}

TEST(ModelFileErrors, AnotherPipelineVersion) {
  TempDir dir;
  auto json = saved_json(dir);
  json["axes"][1]["pipeline"]["version"] = 7;
  const auto error = load_error(dir.write("p.json", json.dump()));
  EXPECT_TRUE(contains(error.message(), "axis 2")) << error.what();
  EXPECT_TRUE(contains(error.message(), "pipeline version 7")) << error.what();
}

// Fuzzing found a version of 1e68: read as an int it is undefined behaviour, so integer
// fields are checked for type and range before they are converted.
TEST(ModelFileErrors, IntegerFieldsOutOfRangeOrFractional) {
  TempDir dir;
  for (const auto& [pointer, value, field] :
       {std::tuple{"/version", nlohmann::json(1e68), "version"},
        std::tuple{"/version", nlohmann::json(1.5), "version"},
        std::tuple{"/axes/0/pipeline/version", nlohmann::json(-1e30), "pipeline version"},
        std::tuple{"/axes/1/pipeline/decimation", nlohmann::json(-3), "decimation"},
        std::tuple{"/axes/1/pipeline/decimation", nlohmann::json(2.0), "decimation"}}) {
    auto json = saved_json(dir);
    json[nlohmann::json::json_pointer(pointer)] = value;
    const auto error = load_error(dir.write("bad.json", json.dump(1)));
    EXPECT_TRUE(contains(error.message(), std::string(field) + " must be an integer from")) << error.what();
  }
}

TEST(ModelFileErrors, NotAModelFile) {
  TempDir dir;
  EXPECT_TRUE(contains(load_error(dir.write("a.json", "[1, 2]")).message(), "not a thermodrift model file"));
  EXPECT_TRUE(contains(load_error(dir.write("b.json", "{\"format\": \"other\"}")).message(),
                       "not a thermodrift model file"));
  EXPECT_TRUE(contains(load_error(dir.file("missing.json")).message(), "cannot open"));
}

// Line and column (1-based) of the position just past the last character of `text`.
std::pair<std::size_t, std::size_t> end_of(const std::string& text) {
  std::size_t line = 1, column = 1;
  for (char c : text) {
    if (c == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

TEST(ModelFileErrors, TruncatedFileNamesWhereItEnds) {
  TempDir dir;
  const std::string whole = saved_json(dir).dump(1);
  for (std::size_t cut : {whole.size() / 3, whole.size() / 2, whole.size() - 2}) {
    std::string text = whole.substr(0, cut);
    // Cut inside a number or a name the parser might still accept as a prefix; cut at a
    // character that leaves the document open.
    while (!text.empty() && (text.back() == ' ' || text.back() == '\n')) text.pop_back();
    const auto path = dir.write("cut.json", text);
    const auto error = load_error(path);
    const auto [line, column] = end_of(text);
    EXPECT_EQ(error.line(), line) << "cut at " << cut << ": " << error.what();
    EXPECT_EQ(error.column(), column) << "cut at " << cut << ": " << error.what();
    EXPECT_TRUE(contains(error.message(), "ends early")) << error.what();
    EXPECT_TRUE(contains(error.what(), path + ":" + std::to_string(line) + ":" + std::to_string(column)));
  }
}

TEST(ModelFileErrors, EmptyFile) {
  TempDir dir;
  const auto error = load_error(dir.write("empty.json", ""));
  EXPECT_EQ(error.line(), 1u);
  EXPECT_EQ(error.column(), 1u);
  EXPECT_TRUE(contains(error.message(), "ends early")) << error.what();
}

TEST(ModelFileErrors, SyntaxErrorNamesItsLineAndColumn) {
  TempDir dir;
  const auto error = load_error(dir.write("bad.json", "{\n  \"format\": \"thermodrift-model\",\n  \"version\": 1x\n}\n"));
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 15u);  // the 'x'
  EXPECT_TRUE(contains(error.message(), "not valid JSON")) << error.what();
}

// Fuzzing found a valid model with an extra key holding arrays nested 30,000 deep: every
// command that loaded it crashed with the stack overflowed.
TEST(ModelFileErrors, DeepNestingIsRefusedWhereItPassesTheLimit) {
  TempDir dir;
  std::string text = saved_json(dir).dump(1);
  const std::size_t depth = 30000;
  const std::string nested = "\"x\": " + std::string(depth, '[') + std::string(depth, ']') + ", ";
  const std::size_t at = text.find("\"gyro_unit\"");
  text.insert(at, nested);
  const auto error = load_error(dir.write("deep.json", text));
  // The 100th '[': the file's own object is the first level.
  const auto [line, column] = end_of(text.substr(0, at + 5 + 100));
  EXPECT_EQ(error.line(), line) << error.what();
  EXPECT_EQ(error.column(), column - 1) << error.what();
  EXPECT_TRUE(contains(error.message(), "nested more than 100 deep")) << error.what();
  // Brackets in strings are text, and the model's own nesting is far from the limit.
  std::string quoted = saved_json(dir).dump(1);
  quoted.insert(quoted.find("\"gyro_unit\""), "\"note\": \"" + std::string(500, '[') + "\", ");
  EXPECT_NO_THROW(load_drift_model(dir.write("quoted.json", quoted)));

  // Through the API, the JSON was never scanned as text.
  const auto json = nlohmann::json::parse(text);
  try {
    drift_model_from_json(json, "api.json");
    ADD_FAILURE() << "accepted the nesting";
  } catch (const DataError& e) {
    EXPECT_TRUE(contains(e.message(), "nested more than 100 deep")) << e.what();
  }
}

// A linear model's prediction costs terms × regressors per sample: 5,000 terms per axis
// took minutes to evaluate. libsvm-format models have a term per column, as many as the
// reader gives a fit.
TEST(ModelFileErrors, TooManyTermsPerAxis) {
  TempDir dir;
  auto with_terms = [&](std::size_t count) {
    DriftModel model = two_axis_model();
    auto& axis = model.axes[0];
    axis.pipeline.terms.clear();
    for (std::size_t i = 0; i < count; ++i) axis.pipeline.terms.push_back(FeatureTerm::parse(fmt::format("lag:{}", i + 1)));
    auto& linear = std::get<LinearModel>(axis.model);
    linear.regressors = linear_regressors(count);
    linear.coefficients = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(count), 0.5);
    axis.fit.terms = axis.pipeline.term_names();
    return to_json(model);
  };
  EXPECT_NO_THROW(load_drift_model(dir.write("most.json", with_terms(kMaxPipelineTerms).dump())));
  const auto error = load_error(dir.write("many.json", with_terms(kMaxPipelineTerms + 1).dump()));
  EXPECT_TRUE(contains(error.message(), "axis 1: 257 feature terms for one axis; at most 256 are allowed"))
      << error.what();
}

// A subnormal feature_scale (5e-324) loaded, and every prediction was NaN: evaluate printed
// NaN metrics, compensate wrote NaN rows and export put it in the C header. Every divisor
// a model file gives is checked.
TEST(ModelFileErrors, ScalesAndRatesTooSmallToDivideBy) {
  const SvrModel svr = small_svr();
  auto body = svr.to_json(kSvrTerms);
  body["feature_scale"][1] = 5e-324;
  EXPECT_EQ(refusal(body), "model.feature_scale[1] is 4.94066e-324: a scale must be at least 1e-12 (features are "
                           "divided by it)");
  body["feature_scale"][1] = 1e-13;
  EXPECT_TRUE(contains(refusal(body), "model.feature_scale[1] is 1e-13")) << refusal(body);
  body["feature_scale"][1] = kMinStandardScale;
  EXPECT_EQ(refusal(body), "accepted");
  body = svr.to_json(kSvrTerms);
  body["target_scale"] = 5e-324;
  EXPECT_TRUE(contains(refusal(body), "target_scale must be positive, at least 1e-12, not 4.94066e-324"))
      << refusal(body);
  body = svr.to_json(kSvrTerms);
  body.erase("sigma");
  body["gamma"] = 5e-324;
  EXPECT_TRUE(contains(refusal(body), "gamma 4.94066e-324 is too small")) << refusal(body);

  TempDir dir;
  auto json = saved_json(dir);
  json["rate_hz"] = 5e-324;
  const auto error = load_error(dir.write("rate.json", json.dump()));
  EXPECT_TRUE(contains(error.message(), "rate_hz is 4.94066e-324: a sampling rate must be at least 1e-12 Hz"))
      << error.what();
}

// A file refused for what a value means is named at the part that holds it: the axis'
// model, its pipeline, the number itself.
TEST(ModelFileErrors, WrongNumberOfCoefficients) {
  TempDir dir;
  auto json = saved_json(dir);
  json["axes"][0]["model"]["coefficients"].push_back(1.0);
  const std::string text = json.dump(1);
  const auto error = load_error(dir.write("coef.json", text));
  EXPECT_EQ(std::pair(error.line(), error.column()), position_in(text, "\"model\": {", 9));
  EXPECT_TRUE(contains(error.message(), "axis 1: 3 coefficients for 2 regressors")) << error.what();
  // The second axis' pipeline: the same key further down.
  json = saved_json(dir);
  json["axes"][1]["pipeline"]["smooth_seconds"] = -3;
  const std::string second = json.dump(1);
  const auto pipeline = load_error(dir.write("smooth.json", second));
  EXPECT_EQ(std::pair(pipeline.line(), pipeline.column()), position_in(second, "\"pipeline\": {", 12, 1));
  EXPECT_TRUE(contains(pipeline.message(), "axis 2: smoothing window must be >= 0 s")) << pipeline.what();
  // On one line, the column tells them apart.
  const auto compact = load_error(dir.write("compact.json", json.dump()));
  EXPECT_EQ(compact.line(), 1u);
  EXPECT_EQ(compact.column(), position_in(json.dump(), "\"pipeline\":{", 11, 1).second);
}

TEST(ModelFileErrors, RegressorOfAnUnknownTerm) {
  TempDir dir;
  auto json = saved_json(dir);
  json["axes"][0]["model"]["regressors"][1] = "humidity";
  const auto error = load_error(dir.write("term.json", json.dump()));
  EXPECT_TRUE(contains(error.message(), "unknown term 'humidity'")) << error.what();
}

TEST(ModelFileErrors, NonFiniteNumbers) {
  TempDir dir;
  const std::string text = saved_json(dir).dump();
  auto replace_intercept = [&](const std::string& value) {
    auto json = nlohmann::json::parse(text);
    json["axes"][1]["model"]["intercept"] = 12345.5;
    std::string edited = json.dump();
    const auto at = edited.find("12345.5");
    return edited.replace(at, 7, value);
  };
  // JSON has no infinity; an overflowing literal is the nearest a file gets to one.
  auto error = load_error(dir.write("inf.json", replace_intercept("1e999")));
  EXPECT_EQ(error.line(), 0u);
  EXPECT_TRUE(contains(error.message(), "1e999")) << error.what();
  EXPECT_TRUE(contains(error.what(), "inf.json: ")) << error.what();

  error = load_error(dir.write("coef.json", replace_intercept("-1e400")));
  EXPECT_TRUE(contains(error.message(), "-1e400")) << error.what();

  // A NaN is written as null.
  error = load_error(dir.write("null.json", replace_intercept("null")));
  EXPECT_TRUE(contains(error.message(), "axis 2")) << error.what();

  // Through the JSON API a true infinity or NaN can reach the loader.
  for (double bad : {INFINITY, -INFINITY, NAN}) {
    auto json = nlohmann::json::parse(text);
    json["axes"][0]["model"]["coefficients"][1] = bad;
    try {
      drift_model_from_json(json, "api.json");
      ADD_FAILURE() << "accepted coefficient " << bad;
    } catch (const DataError& e) {
      EXPECT_TRUE(contains(e.message(), "axis 1: non-finite coefficient")) << e.what();
    }
    json = nlohmann::json::parse(text);
    json["axes"][1]["model"]["intercept"] = bad;
    EXPECT_THROW(drift_model_from_json(json, "api.json"), DataError) << bad;
  }
}

// Finite but absurd numbers would give inf or garbage drift on every sample, and a
// file that says two things at once (a key twice, sigma against gamma) has no one reading.
TEST(ModelFileErrors, AbsurdNumbersDuplicateKeysAndDisagreeingSigma) {
  TempDir dir;
  auto json = saved_json(dir);
  json["axes"][0]["model"]["coefficients"][0] = 1e308;
  auto error = load_error(dir.write("huge.json", json.dump(1)));
  EXPECT_EQ(std::pair(error.line(), error.column()), position_in(json.dump(1), "1e+308"));
  EXPECT_TRUE(contains(error.message(), "axis 1: model.coefficients[0] is 1e+308, beyond the ±1e+12")) << error.what();
  json = saved_json(dir);
  json["axes"][1]["pipeline"]["reference_temperature"] = nullptr;
  error = load_error(dir.write("null.json", json.dump()));
  EXPECT_TRUE(contains(error.message(), "axis 2: pipeline.reference_temperature is null, not a finite number"))
      << error.what();
  EXPECT_EQ(error.column(), position_in(json.dump(), "null").second);
  json = saved_json(dir);
  json["rate_hz"] = -3e15;
  EXPECT_TRUE(contains(load_error(dir.write("rate.json", json.dump())).message(), "rate_hz is -3e+15, beyond"));
  // The informational fit record may hold anything.
  json = saved_json(dir);
  json["axes"][0]["fit"]["mse_before"] = 4e20;
  json["axes"][0]["fit"]["note"] = nullptr;
  EXPECT_NO_THROW(load_drift_model(dir.write("fit.json", json.dump())));

  std::string text = saved_json(dir).dump(1);
  text.replace(text.find("\"gyro_unit\""), 0, "\"gyro_unit\": \"dph\", ");
  error = load_error(dir.write("twice.json", text));
  EXPECT_TRUE(contains(error.message(), "key \"gyro_unit\" appears twice in one object")) << error.what();

  const SvrModel svr = small_svr();
  EXPECT_EQ(refusal(svr.to_json(kSvrTerms)), "accepted");
  auto body = svr.to_json(kSvrTerms);
  body["target_scale"] = 0;
  EXPECT_TRUE(contains(refusal(body), "target_scale must be positive")) << refusal(body);
  body = svr.to_json(kSvrTerms);
  body["sigma"] = 3.0;
  EXPECT_TRUE(contains(refusal(body), "sigma 3 disagrees with gamma 0.5")) << refusal(body);
}

// fit never writes what it could not load again.
TEST(ModelFileErrors, AModelThatWouldNotLoadIsNotWritten) {
  TempDir dir;
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), 5e295}) {
    DriftModel model = two_axis_model();
    std::get<LinearModel>(model.axes[1].model).intercept = bad;
    try {
      save_drift_model(model, dir.file("m.json"));
      ADD_FAILURE() << "saved an intercept of " << bad;
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "the fitted model is not usable, nothing written: axis 2: model.intercept"))
          << e.what();
    }
    EXPECT_TRUE(dir.entries().empty());
  }
}

TEST(ModelFileErrors, UnknownKindAndBadUnit) {
  TempDir dir;
  auto json = saved_json(dir);
  json["axes"][0]["kind"] = "neural";
  EXPECT_TRUE(contains(load_error(dir.write("kind.json", json.dump())).message(), "unknown model kind 'neural'"));
  json = saved_json(dir);
  json["gyro_unit"] = "mph";
  EXPECT_TRUE(contains(load_error(dir.write("unit.json", json.dump())).message(), "unknown gyro unit"));
  json = saved_json(dir);
  json["axes"] = nlohmann::json::array();
  EXPECT_TRUE(contains(load_error(dir.write("axes.json", json.dump())).message(), "no axes"));
  json = saved_json(dir);
  json["axes"][0].erase("pipeline");
  EXPECT_TRUE(contains(load_error(dir.write("nopipe.json", json.dump())).message(), "axis 1"));
}

}  // namespace
}  // namespace thermodrift
