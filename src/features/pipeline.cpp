#include "thermodrift/features/pipeline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "thermodrift/error.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/io/json_integer.hpp"
#include "thermodrift/io/libsvm_reader.hpp"

namespace thermodrift {

double Pipeline::effective_gap_seconds() const {
  return gap_seconds > 0 ? gap_seconds : std::max(smooth_seconds, 10.0);
}

std::vector<std::string> Pipeline::term_names() const {
  std::vector<std::string> names;
  for (const auto& term : terms) names.push_back(term.name());
  return names;
}

std::vector<std::size_t> Pipeline::channels() const {
  std::vector<std::size_t> out;
  for (const auto& term : terms) {
    for (const std::size_t channel : term.channels()) out.push_back(channel);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

double Pipeline::longest_delay() const {
  double longest = 0;
  for (const auto& term : terms) {
    for (const auto& factor : term.factors) longest = std::max(longest, factor.atom.tau + factor.atom.tau2);
  }
  return longest;
}

void Pipeline::validate() const {
  auto finite_nonnegative = [](double value) { return std::isfinite(value) && value >= 0; };
  if (!finite_nonnegative(smooth_seconds)) {
    throw UsageError(fmt::format("smoothing window must be >= 0 s, not {}", smooth_seconds));
  }
  if (!(std::isfinite(rate_span_seconds) && rate_span_seconds > 0)) {
    throw UsageError(fmt::format("rate span must be > 0 s, not {}", rate_span_seconds));
  }
  if (!finite_nonnegative(gap_seconds)) {
    throw UsageError(fmt::format("gap threshold must be >= 0 s, not {}", gap_seconds));
  }
  if (decimation < 1) throw UsageError("decimation must be at least 1");
  if (!plausible_temperature(reference_temperature)) {  // a model file's number within ±1e12 may still be absurd
    throw UsageError(fmt::format("reference temperature {:g} °C is beyond {:g}..{:g} °C", reference_temperature,
                                 kMinTemperatureC, kMaxTemperatureC));
  }
  if (terms.empty()) throw UsageError("a pipeline needs at least one feature term");
  if (!libsvm && terms.size() > kMaxPipelineTerms) {
    throw UsageError(fmt::format("{} feature terms for one axis; at most {} are allowed", terms.size(),
                                 kMaxPipelineTerms));
  }
  if (temperature_channel && *temperature_channel >= kMaxTemperatureChannels) {
    throw UsageError(fmt::format("temperature channel {} is beyond the {} a model can read",
                                 *temperature_channel + 1, kMaxTemperatureChannels));
  }
}

Pipeline Pipeline::libsvm_input(std::size_t columns) {
  Pipeline pipeline;
  pipeline.libsvm = true;
  pipeline.smooth_seconds = 0;
  pipeline.terms.clear();
  for (std::size_t j = 0; j < columns; ++j) {
    pipeline.terms.emplace_back(FeatureAtom{FeatureTerm::Kind::input, 0, 0, j});
  }
  return pipeline;
}

nlohmann::json Pipeline::to_json() const {
  if (libsvm) return {{"version", kVersion}, {"input", "libsvm"}, {"terms", term_names()}};
  nlohmann::json json = {{"version", kVersion},
                         {"smooth_seconds", smooth_seconds},
                         {"window", "trailing"},
                         {"rate_span_seconds", rate_span_seconds},
                         {"gap_seconds", effective_gap_seconds()},
                         {"decimation", decimation},
                         {"reference_temperature", reference_temperature},
                         {"terms", term_names()}};
  // 1-based, like the channels of grad:A-B.
  if (temperature_channel) json["temperature_channel"] = *temperature_channel + 1;
  return json;
}

Pipeline Pipeline::from_json(const nlohmann::json& json) {
  if (json_integer<int>(json.at("version"), "pipeline version") != kVersion) {
    throw Error(fmt::format("pipeline version {} is not supported (expected {})",
                            json.at("version").dump(), kVersion));
  }
  if (json.value("input", "chamber_log") == "libsvm") {
    const auto& names = json.at("terms");
    // As many as the libsvm reader gives a fit; checked before a term is made of each.
    if (!names.is_array() || names.size() > static_cast<std::size_t>(kMaxLibsvmFeatureIndex)) {
      throw Error(fmt::format("a libsvm pipeline's terms must be a list of at most {}", kMaxLibsvmFeatureIndex));
    }
    Pipeline pipeline = libsvm_input(names.size());
    if (pipeline.term_names() != json.at("terms").get<std::vector<std::string>>()) {
      throw Error("libsvm pipeline terms must be x1..xN");
    }
    return pipeline;
  }
  if (json.at("window").get<std::string>() != "trailing") {
    throw Error("pipeline window must be \"trailing\"");
  }
  Pipeline pipeline;
  pipeline.smooth_seconds = json.at("smooth_seconds").get<double>();
  pipeline.rate_span_seconds = json.at("rate_span_seconds").get<double>();
  pipeline.gap_seconds = json.at("gap_seconds").get<double>();
  pipeline.decimation = json_integer<std::size_t>(json.at("decimation"), "decimation");
  pipeline.reference_temperature = json.at("reference_temperature").get<double>();
  if (json.contains("temperature_channel")) {
    const auto channel = json_integer<std::size_t>(json.at("temperature_channel"), "temperature_channel");
    if (channel < 1) throw Error("temperature_channel counts from 1");
    pipeline.temperature_channel = channel - 1;
  }
  pipeline.terms.clear();
  for (const auto& term : json.at("terms")) pipeline.terms.push_back(FeatureTerm::parse(term.get<std::string>()));
  pipeline.validate();
  return pipeline;
}

std::size_t default_decimation(double smooth_seconds, double sample_interval_seconds) {
  if (!(sample_interval_seconds > 0)) return 1;
  const double per_window = smooth_seconds / sample_interval_seconds;
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(per_window / 10.0)));
}

SmoothedChannel::SmoothedChannel(double smooth_seconds, double rate_span_seconds)
    : mean_(smooth_seconds), span_(rate_span_seconds) {}

void SmoothedChannel::reset() {
  mean_.reset();
  history_.clear();
  history_head_ = 0;
}

SmoothedChannel::Value SmoothedChannel::push(double time, double temperature) {
  const double smoothed = mean_.push(time, temperature);
  // Compacted when half dead, so the cost stays O(1) amortised with no per-sample allocation.
  history_.push_back({time, smoothed});
  while (history_.size() - history_head_ >= 2 && history_[history_head_ + 1].time <= time - span_) {
    ++history_head_;
  }
  if (history_head_ > 64 && history_head_ * 2 > history_.size()) {
    history_.erase(history_.begin(), history_.begin() + static_cast<std::ptrdiff_t>(history_head_));
    history_head_ = 0;
  }
  const Stamped& past = history_[history_head_];
  const double elapsed = time - past.time;
  return {smoothed, elapsed > 0 ? (smoothed - past.value) / elapsed * 60.0 : 0.0};
}

FeatureStream::FeatureStream(const Pipeline& pipeline)
    : pipeline_(&pipeline),
      gyro_mean_(pipeline.smooth_seconds),
      temperature_(pipeline.smooth_seconds, pipeline.rate_span_seconds),
      channels_(pipeline.channels()),
      channel_filters_(channels_.size(), SmoothedChannel(pipeline.smooth_seconds, pipeline.rate_span_seconds)),
      channel_means_(channels_.empty() ? 0 : channels_.back() + 1),
      channel_rates_(channel_means_.size()),
      terms_(pipeline.terms),
      features_(pipeline.terms.size()) {
  sample_.features = features_;
}

void FeatureStream::reset() {
  gyro_mean_.reset();
  temperature_.reset();
  for (auto& filter : channel_filters_) filter.reset();
  started_ = false;
}

const FeatureStream::Sample& FeatureStream::push(double time, double gyro, double temperature,
                                                 std::span<const double> channels) {
  if (started_ && time - last_time_ > pipeline_->effective_gap_seconds()) reset();
  const double step_seconds = started_ ? time - last_time_ : 0.0;  // 0: lags start in equilibrium
  if (!started_) {
    started_ = true;
    start_time_ = time;
  }
  last_time_ = time;
  sample_.smoothed_gyro = gyro_mean_.push(time, gyro);
  sample_.window_lag = (time - gyro_mean_.oldest_time()) / 2;
  const SmoothedChannel::Value own = temperature_.push(time, temperature);
  sample_.smoothed_temperature = own.mean;
  sample_.smoothed_rate = own.rate;
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    const std::size_t channel = channels_[i];
    if (channel >= channels.size()) {
      throw UsageError(fmt::format("the feature terms read temperature channel {}, but {} channel(s) are given",
                                   channel + 1, channels.size()));
    }
    const SmoothedChannel::Value value = channel_filters_[i].push(time, channels[channel]);
    channel_means_[channel] = value.mean;
    channel_rates_[channel] = value.rate;
  }
  inputs_ = {own.mean - pipeline_->reference_temperature, own.rate, step_seconds, channel_means_, channel_rates_};
  terms_.push(inputs_, features_);
  sample_.since_start = time - start_time_;
  sample_.step_seconds = step_seconds;
  sample_.ready = sample_.since_start >= pipeline_->warm_up_seconds();
  return sample_;
}

namespace {

// Streams one axis of a log through `pipeline`: visit(row, sample, stream, kept) for every
// row, `kept` for the ready rows a (decimated) table keeps.
template <class Visit>
void stream_log(const Pipeline& pipeline, const ChamberLog& log, std::size_t gyro_axis, std::size_t temperature_channel,
                bool decimate, Visit&& visit) {
  // Burst means are a burst period apart: steps up to two missed bursts join them.
  Pipeline joined = pipeline;
  if (log.bursts) joined.gap_seconds = std::max(pipeline.effective_gap_seconds(), log.bursts->gap_seconds());
  FeatureStream stream(joined);
  const std::size_t step = decimate ? pipeline.decimation : 1;
  std::size_t ready_count = 0;
  std::vector<double> channels(pipeline.channels().empty() ? 0 : log.temperature.size());
  const std::size_t node_channel = pipeline.temperature_input(temperature_channel);
  if (node_channel >= log.temperature.size()) {
    throw UsageError(fmt::format("the model computes ΔT from temperature channel {}, but {} channel(s) are given",
                                 node_channel + 1, log.temperature.size()));
  }
  for (std::size_t i = 0; i < log.rows(); ++i) {
    for (std::size_t c = 0; c < channels.size(); ++c) channels[c] = log.temperature[c][i];
    const auto& sample = stream.push(log.time[i], log.gyro[gyro_axis][i], log.temperature[node_channel][i], channels);
    bool kept = false;
    if (!sample.ready) {
      ready_count = 0;  // decimation restarts with each warm-up
    } else {
      kept = ready_count++ % step == 0;
    }
    visit(i, sample, stream, kept);
  }
}

}  // namespace

FeatureTable build_feature_table(const Pipeline& pipeline, const ChamberLog& log,
                                 std::size_t gyro_axis, std::size_t temperature_channel,
                                 bool decimate) {
  std::vector<double> flat;
  std::vector<double> target;
  FeatureTable table;
  table.run_start = {0};
  stream_log(pipeline, log, gyro_axis, temperature_channel, decimate,
             [&](std::size_t i, const FeatureStream::Sample& sample, const FeatureStream&, bool kept) {
               if (!kept) return;
               flat.insert(flat.end(), sample.features.begin(), sample.features.end());
               target.push_back(sample.smoothed_gyro);
               table.time.push_back(log.time[i]);
               table.since_start.push_back(sample.since_start);
               table.temperature.push_back(sample.smoothed_temperature);
               table.rate.push_back(sample.smoothed_rate);
               table.row.push_back(i);
             });
  const auto n = static_cast<Eigen::Index>(table.row.size());
  const auto d = static_cast<Eigen::Index>(pipeline.terms.size());
  table.features = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic,
                                                  Eigen::RowMajor>>(flat.data(), n, d);
  table.target = Eigen::Map<const Eigen::VectorXd>(target.data(), n);
  return table;
}

RecordedInputs record_inputs(const Pipeline& pipeline, const ChamberLog& log, std::size_t gyro_axis,
                             std::size_t temperature_channel, bool decimate) {
  RecordedInputs recorded;
  recorded.channels = pipeline.channels();
  recorded.delta_t.reserve(log.rows());
  recorded.rate.reserve(log.rows());
  recorded.step_seconds.reserve(log.rows());
  recorded.channel_means.reserve(log.rows() * recorded.width());
  recorded.channel_rates.reserve(log.rows() * recorded.width());
  stream_log(pipeline, log, gyro_axis, temperature_channel, decimate,
             [&](std::size_t i, const FeatureStream::Sample& sample, const FeatureStream& stream, bool kept) {
               const TermInputs& in = stream.inputs();
               recorded.delta_t.push_back(in.delta_t);
               recorded.rate.push_back(in.rate);
               recorded.step_seconds.push_back(in.step_seconds);
               recorded.channel_means.insert(recorded.channel_means.end(), in.channel_means.begin(), in.channel_means.end());
               recorded.channel_rates.insert(recorded.channel_rates.end(), in.channel_rates.begin(), in.channel_rates.end());
               if (!kept) return;
               recorded.kept.push_back(i);
               recorded.target.push_back(sample.smoothed_gyro);
             });
  return recorded;
}

Eigen::MatrixXd evaluate_terms(const std::vector<FeatureTerm>& terms, const RecordedInputs& inputs) {
  for (const auto& term : terms) {
    for (const std::size_t channel : term.channels()) {
      if (!std::binary_search(inputs.channels.begin(), inputs.channels.end(), channel)) {
        throw UsageError(fmt::format("feature term '{}' reads temperature channel {}, which was not recorded",
                                     term.name(), channel + 1));
      }
    }
  }
  const bool sparse = inputs.dense_step_seconds > 0;
  TermEvaluator evaluator(terms, sparse ? InputHold::linear : InputHold::step, inputs.dense_step_seconds / 2);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out(
      static_cast<Eigen::Index>(inputs.kept.size()), static_cast<Eigen::Index>(terms.size()));
  std::vector<double> values(terms.size());
  std::size_t next = 0;
  const std::size_t width = inputs.width();
  for (std::size_t i = 0; i < inputs.rows() && next < inputs.kept.size(); ++i) {
    const TermInputs in{inputs.delta_t[i], inputs.rate[i], inputs.step_seconds[i],
                        std::span<const double>(inputs.channel_means).subspan(i * width, width),
                        std::span<const double>(inputs.channel_rates).subspan(i * width, width)};
    if (inputs.kept[next] != i) {
      evaluator.advance(in);
      continue;
    }
    evaluator.push(in, values);
    for (std::size_t j = 0; j < terms.size(); ++j) out(static_cast<Eigen::Index>(next), static_cast<Eigen::Index>(j)) = values[j];
    ++next;
  }
  return out;
}

RecordedInputs sparse_inputs(const RecordedInputs& inputs, std::size_t every) {
  RecordedInputs sparse;
  sparse.channels = inputs.channels;
  sparse.target = inputs.target;
  std::vector<double> steps;
  for (const double step : inputs.step_seconds) {
    if (step > 0) steps.push_back(step);
  }
  if (!steps.empty()) {
    const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), middle, steps.end());
    sparse.dense_step_seconds = *middle;
  }
  const std::size_t width = inputs.width();
  std::size_t next = 0;  // the next kept row
  std::size_t last = 0;  // the last row taken
  double elapsed = 0;    // since it
  for (std::size_t i = 0; i < inputs.rows(); ++i) {
    const bool restart = !(inputs.step_seconds[i] > 0);
    elapsed = restart ? 0.0 : elapsed + inputs.step_seconds[i];
    const bool kept = next < inputs.kept.size() && inputs.kept[next] == i;
    if (!(restart || kept || i == 0 || i - last >= every)) continue;
    if (kept) {
      sparse.kept.push_back(sparse.rows());
      ++next;
    }
    sparse.delta_t.push_back(inputs.delta_t[i]);
    sparse.rate.push_back(inputs.rate[i]);
    sparse.step_seconds.push_back(elapsed);
    sparse.channel_means.insert(sparse.channel_means.end(), inputs.channel_means.begin() + static_cast<std::ptrdiff_t>(i * width),
                                inputs.channel_means.begin() + static_cast<std::ptrdiff_t>((i + 1) * width));
    sparse.channel_rates.insert(sparse.channel_rates.end(), inputs.channel_rates.begin() + static_cast<std::ptrdiff_t>(i * width),
                                inputs.channel_rates.begin() + static_cast<std::ptrdiff_t>((i + 1) * width));
    last = i;
    elapsed = 0;
  }
  return sparse;
}

void append_rows(FeatureTable& table, const FeatureTable& more) {
  if (table.rows() == 0) {
    table = more;
    return;
  }
  const auto n = table.features.rows();
  table.features.conservativeResize(n + more.features.rows(), Eigen::NoChange);
  table.features.bottomRows(more.features.rows()) = more.features;
  table.target.conservativeResize(n + more.target.size());
  table.target.tail(more.target.size()) = more.target;
  table.time.insert(table.time.end(), more.time.begin(), more.time.end());
  table.since_start.insert(table.since_start.end(), more.since_start.begin(), more.since_start.end());
  table.temperature.insert(table.temperature.end(), more.temperature.begin(), more.temperature.end());
  table.rate.insert(table.rate.end(), more.rate.begin(), more.rate.end());
  table.row.insert(table.row.end(), more.row.begin(), more.row.end());
  for (const std::size_t start : more.run_start) table.run_start.push_back(static_cast<std::size_t>(n) + start);
}

}  // namespace thermodrift
