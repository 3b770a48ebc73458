#include "thermodrift/compensate/c_export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>

#include "thermodrift/error.hpp"
#include "thermodrift/features/moving_average.hpp"
#include "thermodrift/features/terms.hpp"
#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift {

namespace {

// The C++ TrailingMean starts with room for 16 samples and doubles; its exact re-sum
// runs every `ring size` pushes. The header mirrors that period (not the allocation) so
// that both round the same way.
constexpr std::size_t kTrailingMeanInitialCapacity = 16;
// A state larger than this is a wrong --max-rate, not a device.
constexpr double kMaxRingEntries = 1e8;
constexpr double kDefaultMaxRateHz = 100;

bool valid_identifier(const std::string& name) {
  if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_')) return false;
  return std::all_of(name.begin(), name.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

std::string upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// C comments must not be closed by text taken from a model file.
std::string comment_safe(std::string text) {
  for (std::size_t at = text.find("*/"); at != std::string::npos; at = text.find("*/")) text.replace(at, 2, "* /");
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

// Filter states per axis in the exported state: two per factor (see TermEvaluator).
std::size_t filter_slots(const DriftModel& model) {
  std::size_t slots = 1;
  for (const auto& axis : model.axes) {
    std::size_t factors = 0;
    for (const auto& term : axis.pipeline.terms) factors += term.factors.size();
    slots = std::max(slots, factors);
  }
  return slots;
}

// Temperature channels per axis smoothed for grad terms (the most any axis reads).
std::size_t grad_channel_slots(const DriftModel& model) {
  std::size_t slots = 0;
  for (const auto& axis : model.axes) slots = std::max(slots, axis.pipeline.channels().size());
  return slots;
}

// Per sample cost of the lags of one factor: exp calls and other flops.
std::pair<std::size_t, std::size_t> factor_cost(const FeatureFactor& factor) {
  using Kind = FeatureAtom::Kind;
  const std::size_t powers = static_cast<std::size_t>(factor.power);
  switch (factor.atom.kind) {
    case Kind::lag: return {1, 4 + powers};
    case Kind::hinge: return {1, 6 + powers};
    case Kind::lead: return {0, 3 + powers};
    case Kind::lead_hinge: return {0, 5 + powers};
    case Kind::lag2: return {2, 8 + powers};
    case Kind::lag2_rate: return {2, 11 + powers};
    case Kind::node_hinge: return {factor.atom.tau2 > 0 ? 2 : 1, 14 + powers};
    case Kind::play: return {1, 10 + powers};
    case Kind::lag_rate: return {1, 7 + powers};
    case Kind::gradient_rate: return {2, 14 + powers};
    case Kind::direction: return {factor.atom.tau2 > 0 ? 3 : 2, (factor.atom.tau2 > 0 ? 14 : 9) + powers};
    case Kind::channel_gradient:
    case Kind::channel_gradient_rate: return {0, 1 + powers};
    default: return {0, powers};
  }
}

void check_exportable(const DriftModel& model) {
  if (model.axes.empty()) throw UsageError("the model has no axes to export");
  for (const auto& axis : model.axes) {
    if (axis.pipeline.libsvm) {
      throw UsageError("a model fitted on libsvm-format data has no chamber-log pipeline to export");
    }
    for (const auto& term : axis.pipeline.terms) {
      if (term.uses_input()) {
        throw UsageError(fmt::format("axis {}: feature term {} cannot be computed on a device", axis.name,
                                     term.name()));
      }
    }
  }
}

// Literals that read back to the same value in the header's precision.
class Literal {
 public:
  explicit Literal(bool single_precision) : single_(single_precision) {}

  std::string operator()(double value) const {
    std::string text = single_ ? fmt::format("{}", static_cast<float>(value)) : fmt::format("{}", value);
    if (text.find_first_of(".eE") == std::string::npos) text += ".0";
    if (single_) text += 'f';
    return text;
  }
  // Time constants are always double: a float clock loses sub-sample resolution in hours.
  static std::string time(double value) {
    std::string text = fmt::format("{}", value);
    if (text.find_first_of(".eE") == std::string::npos) text += ".0";
    return text;
  }

 private:
  bool single_;
};

void append_array(std::string& out, const Literal& literal, const double* values, std::size_t count,
                  std::size_t per_line = 4) {
  for (std::size_t i = 0; i < count; ++i) {
    out += (i % per_line == 0) ? "\n    " : " ";
    out += literal(values[i]);
    if (i + 1 < count) out += ',';
  }
}

// The raw-input conversions, computed as LogSampleReader computes them so that the
// device's deg/h and degC are the compensator's to the bit: gyro factor = unit factor
// times the scale (one product), degC = scale * raw + offset.
void append_input_scaling(std::string& out, const DriftModel& model, const std::string& p, const std::string& P) {
  const Literal literal(false);
  std::vector<double> gyro_factor;
  for (std::size_t a = 0; a < model.axes.size(); ++a) {
    gyro_factor.push_back(degrees_per_hour(model.gyro_unit) * model.scaling.gyro_scale_of(a));
  }
  std::vector<double> scale;
  std::vector<double> offset;
  for (std::size_t c = 0; c < model.temperature_inputs(); ++c) {
    scale.push_back(model.scaling.temperature_scale_of(c));
    offset.push_back(model.scaling.temperature_offset_of(c));
  }
  auto array = [&](const char* name, const char* comment, const char* size, const std::vector<double>& values) {
    out += fmt::format("/* {} */\nstatic const double {}_{}[{}_{}] = {{", comment, p, name, P, size);
    append_array(out, literal, values.data(), values.size());
    out += "\n};\n";
  };
  array("gyro_factor", "deg/h per raw gyro unit, per axis: unit conversion times --gyro-scale", "AXES", gyro_factor);
  array("temperature_scale", "degC = scale * raw + offset, per temperature input (--temp-scale)", "TEMPERATURES", scale);
  array("temperature_offset", "(--temp-offset)", "TEMPERATURES", offset);
  out += "\n";
}

}  // namespace

bool CExportOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& reason) {
    if (error != nullptr) *error = reason;
    return false;
  };
  if (!valid_identifier(prefix)) return fail(fmt::format("prefix '{}' is not a C identifier", prefix));
  if (max_rate_hz && !(std::isfinite(*max_rate_hz) && *max_rate_hz > 0)) {
    return fail(fmt::format("--max-rate must be a positive number of hertz, not {}", *max_rate_hz));
  }
  return true;
}

double export_max_rate_hz(const DriftModel& model, const CExportOptions& options) {
  if (options.max_rate_hz) return *options.max_rate_hz;
  if (model.rate_hz && *model.rate_hz > 0) return *model.rate_hz;
  return kDefaultMaxRateHz;
}

namespace {
std::size_t ring_capacity(double seconds, double max_rate_hz, std::size_t extra) {
  const double entries = std::ceil(seconds * max_rate_hz) + static_cast<double>(extra);
  if (!(entries <= kMaxRingEntries)) {
    throw UsageError(fmt::format("{} s at {} Hz needs {} ring entries per axis; lower --max-rate",
                                 seconds, max_rate_hz, entries));
  }
  return static_cast<std::size_t>(entries);
}
}  // namespace

// Samples strictly increasing at most max_rate apart: (t - W, t] holds at most
// floor(W·rate) + 1 of them after the eviction; one more absorbs rounding of the stamps.
std::size_t mean_ring_capacity(const Pipeline& pipeline, double max_rate_hz) {
  return ring_capacity(pipeline.smooth_seconds, max_rate_hz, 2);
}

// Before the oldest entries are advanced past: the one at or before t' - span, those in
// (t' - span, t'] of the previous sample t', and the new one; plus one for rounding.
std::size_t history_ring_capacity(const Pipeline& pipeline, double max_rate_hz) {
  return ring_capacity(pipeline.rate_span_seconds, max_rate_hz, 3);
}

std::size_t ModelSize::constant_bytes() const {
  return std::accumulate(axes.begin(), axes.end(), std::size_t{0},
                         [](std::size_t sum, const Axis& axis) { return sum + axis.constant_bytes; });
}

std::size_t ModelSize::flops_per_sample() const {
  return std::accumulate(axes.begin(), axes.end(), std::size_t{0},
                         [](std::size_t sum, const Axis& axis) { return sum + axis.flops_per_sample; });
}

std::size_t ModelSize::exp_per_sample() const {
  return std::accumulate(axes.begin(), axes.end(), std::size_t{0},
                         [](std::size_t sum, const Axis& axis) { return sum + axis.exp_per_sample; });
}

std::string ModelSize::table() const {
  std::string out = fmt::format("{:<12} {:<9} {:>8} {:>10} {:>15} {:>11}\n", "axis", "model",
                                "SV/terms", "constants", "flops/sample", "exp/sample");
  for (const auto& axis : axes) {
    const std::size_t count = axis.kind == "svr" ? axis.support_vectors : axis.regressors;
    out += fmt::format("{:<12} {:<9} {:>8} {:>8} B {:>15} {:>11}\n", axis.name, axis.kind, count,
                       axis.constant_bytes, axis.flops_per_sample, axis.exp_per_sample);
  }
  out += fmt::format("{:<12} {:<9} {:>8} {:>8} B {:>15} {:>11}   ({} operations/sample, {})\n", "total", "",
                     "", constant_bytes(), flops_per_sample(), exp_per_sample(), operations_per_sample(),
                     single_precision ? "float" : "double");
  return out;
}

ModelSize model_size(const DriftModel& model, bool single_precision) {
  const std::size_t real = single_precision ? sizeof(float) : sizeof(double);
  // Per axis: trailing mean (add, evict, divide), rate (two subtractions, divide, scale),
  // ΔT, and gyro - drift.
  constexpr std::size_t kPipelineFlops = 9;
  // smooth, span, gap, warm-up (double) and the reference temperature.
  const std::size_t pipeline_bytes = 4 * sizeof(double) + real;
  ModelSize size;
  size.single_precision = single_precision;
  for (const auto& axis_model : model.axes) {
    ModelSize::Axis axis;
    axis.name = axis_model.name;
    axis.kind = axis_model.kind;
    axis.features = axis_model.pipeline.terms.size();
    const std::size_t d = axis.features;
    axis.constant_bytes = pipeline_bytes;
    // Each channel a grad term reads runs the trailing mean and the rate too.
    axis.flops_per_sample = kPipelineFlops * (1 + axis_model.pipeline.channels().size());
    for (const auto& term : axis_model.pipeline.terms) {
      for (const auto& factor : term.factors) {
        const auto [exps, flops] = factor_cost(factor);
        axis.exp_per_sample += exps;
        axis.flops_per_sample += flops;
      }
    }
    if (const auto* svr = std::get_if<SvrModel>(&axis_model.model)) {
      const auto sv = static_cast<std::size_t>(svr->function.support_vectors.rows());
      axis.support_vectors = sv;
      // support vectors, coefficients, feature mean and scale, bias, gamma, target mean and scale
      axis.constant_bytes += (sv * d + sv + 2 * d + 4) * real;
      // standardize (2d), per SV: d subtractions, d multiplies, d additions, -γ·s, c·e^…, sum;
      // un-standardize (2)
      axis.flops_per_sample += 2 * d + sv * (3 * d + 3) + 2;
      axis.exp_per_sample += sv;
      if (svr->linear_part) {
        const auto& regressors = svr->linear_part->regressors;
        axis.regressors = regressors.size();
        axis.constant_bytes += (regressors.size() + 1) * real + regressors.size() * d;
        for (const auto& regressor : regressors) {
          axis.flops_per_sample +=
              static_cast<std::size_t>(std::accumulate(regressor.powers.begin(), regressor.powers.end(), 0)) + 2;
        }
      }
    } else if (const auto* linear = std::get_if<LinearModel>(&axis_model.model)) {
      axis.regressors = linear->regressors.size();
      axis.constant_bytes += (axis.regressors + 1) * real + axis.regressors * d;  // powers as bytes
      for (const auto& regressor : linear->regressors) {
        axis.flops_per_sample += static_cast<std::size_t>(
                                     std::accumulate(regressor.powers.begin(), regressor.powers.end(), 0)) +
                                 2;
      }
    }
    size.axes.push_back(axis);
  }
  return size;
}

std::size_t exported_state_bytes(const DriftModel& model, const CExportOptions& options) {
  const double rate = export_max_rate_hz(model, options);
  std::size_t mean = 0;
  std::size_t history = 0;
  for (const auto& axis : model.axes) {
    mean = std::max(mean, mean_ring_capacity(axis.pipeline, rate));
    history = std::max(history, history_ring_capacity(axis.pipeline, rate));
  }
  // A ring entry is a double time and a value (padded to 16 bytes in both precisions on
  // common ABIs); a few counters and times per axis.
  const std::size_t entry = 16;
  const std::size_t real = options.single_precision ? sizeof(float) : sizeof(double);
  const std::size_t channels = 1 + grad_channel_slots(model);
  return model.axes.size() * (channels * ((mean + history) * entry + 48) + 2 * filter_slots(model) * real + 56);
}

std::string export_c_header(const DriftModel& model, const CExportOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw UsageError(error);
  check_exportable(model);
  const Literal literal(options.single_precision);
  const std::string& p = options.prefix;
  const std::string P = upper(p);
  const std::string exp_name = options.single_precision ? "expf" : "exp";
  const double rate = export_max_rate_hz(model, options);
  std::size_t mean_capacity = 0;
  std::size_t history_capacity = 0;
  for (const auto& axis : model.axes) {
    mean_capacity = std::max(mean_capacity, mean_ring_capacity(axis.pipeline, rate));
    history_capacity = std::max(history_capacity, history_ring_capacity(axis.pipeline, rate));
  }
  const ModelSize size = model_size(model, options.single_precision);
  const std::size_t axes = model.axes.size();
  const std::size_t grad_slots = grad_channel_slots(model);
  const bool single = options.single_precision;
  // A model of a log in raw counts takes them as the log holds them: the device's
  // readings need no conversion that could differ from the one fit used.
  const bool raw = !model.scaling.is_default();
  // In float, running sums (the trailing mean, the SVR's sum over support vectors) are
  // compensated (Kahan), which keeps them within a few ulp of the double result; in
  // double they are plain sums, operation for operation as in C++.
  auto accumulate = [&](const std::string& sum, const std::string& carry, const std::string& value) {
    if (!single) return fmt::format("{} += {};", sum, value);
    return fmt::format("{}_accumulate(&{}, &{}, {});", p, sum, carry, value);
  };

  std::string out;
  out += fmt::format(
      "/* {p}.h: a thermodrift gyro drift model for the navigation computer.\n"
      " * Generated by `thermodrift export`{source}. Do not edit; export again.\n"
      " *\n"
      " * C99, no allocation, no writable globals, libm's {exp} only. Units: {units}\n"
      " * Temperatures: {temperatures}.\n"
      " *\n"
      " *   {p}_state state;            (caller-owned, {state_bytes} bytes; static or global is fine)\n"
      " *   {p}_init(&state);\n"
      " *   for each sample:\n"
      " *     int ready = {p}_step(&state, time_s, {gyro_in}, {temperature_in}, compensated_dph);\n"
      " *\n"
      " * step returns 1 when every axis has {warm} s of history since the start or the last\n"
      " * restart, 0 during warm-up (the output is then the best causal estimate from a partial\n"
      " * window). A time step longer than the gap threshold, or a time that does not\n"
      " * increase, restarts the warm-up. Ring buffers are sized for {rate} Hz: a device that\n"
      " * samples faster drops the oldest sample of a full ring, counts it in\n"
      " * state.dropped_samples and returns 0 for that step (never writes out of bounds).\n"
      " * A sample with a non-finite time, gyro or temperature, a gyro beyond +-3.6e8 deg/h or a\n"
      " * temperature beyond -273.15..1000 degC (a failed read; the ranges thermodrift reads\n"
      " * logs with) is rejected whole: step leaves the state as it was, writes NAN, counts\n"
      " * it in state.rejected_samples and returns 0. An output that is not finite returns 0.\n"
      " *\n"
      " * Model size ({precision}):\n",
      fmt::arg("p", p), fmt::arg("source", options.source.empty() ? "" : " from " + comment_safe(options.source)),
      fmt::arg("exp", exp_name), fmt::arg("state_bytes", exported_state_bytes(model, options)),
      fmt::arg("units", raw ? fmt::format("time in s; gyro and temperature raw, as the\n"
                                          " * log holds them (gyro in {}; scale and offset applied inside, see\n"
                                          " * {}_gyro_factor and {}_temperature_scale/_offset); compensated rates in deg/h.",
                                          to_string(model.gyro_unit), p, p)
                            : std::string("time in s, gyro rates in deg/h, temperatures in degC.")),
      fmt::arg("gyro_in", raw ? "gyro_raw" : "gyro_dph"), fmt::arg("temperature_in", raw ? "temperature_raw" : "temperature_c"),
      fmt::arg("temperatures", model.extra_temperature_columns.empty()
                                   ? std::string("one channel per axis")
                                   : fmt::format("one channel per axis, then {}",
                                                 comment_safe(fmt::format("{}", fmt::join(model.extra_temperature_columns, ", "))))),
      fmt::arg("warm", model.axes.front().pipeline.warm_up_seconds()), fmt::arg("rate", rate),
      fmt::arg("precision", options.single_precision ? "float" : "double"));
  for (const auto& line : {size.table()}) {
    std::size_t begin = 0;
    while (begin < line.size()) {
      const std::size_t end = line.find('\n', begin);
      out += " *   " + comment_safe(line.substr(begin, end - begin)) + "\n";
      begin = end == std::string::npos ? line.size() : end + 1;
    }
  }
  out += " */\n";
  out += fmt::format("#ifndef {P}_H_INCLUDED\n#define {P}_H_INCLUDED\n\n#include <math.h>\n\n", fmt::arg("P", P));
  out += "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
  out += fmt::format(
      "#define {P}_AXES {axes}\n"
      "#define {P}_TEMPERATURES {temperatures}  /* temperature inputs: one per axis, then the grad terms' extra channels */\n"
      "#define {P}_MAX_RATE_HZ {rate}\n"
      "#define {P}_MEAN_CAPACITY {mean}\n"
      "#define {P}_HISTORY_CAPACITY {history}\n"
      "#define {P}_FILTERS {filters}\n"
      "#define {P}_SINGLE_PRECISION {single}\n"
      "#define {P}_RAW_INPUTS {raw}  /* 1: step takes gyro and temperature raw, as the log holds them */\n\n"
      "typedef {real} {p}_real;\n\n"
      "typedef struct {{\n"
      "  double time;\n"
      "  {p}_real value;\n"
      "}} {p}_stamped;\n\n"
      "/* One temperature channel of the feature pipeline: its trailing mean over\n"
      " * (t - smooth, t] and the history of that mean for the backward-difference rate. */\n"
      "typedef struct {{\n"
      "  {p}_stamped mean_ring[{P}_MEAN_CAPACITY];\n"
      "  unsigned long mean_head;\n"
      "  unsigned long mean_count;\n"
      "  unsigned long resum_period;        /* exact re-sum every this many pushes (mirrors the C++ ring) */\n"
      "  unsigned long pushes_since_resum;\n"
      "  {p}_real mean_sum;\n"
      "{carry_field}"
      "  {p}_stamped history[{P}_HISTORY_CAPACITY];\n"
      "  unsigned long history_head;\n"
      "  unsigned long history_count;\n"
      "}} {p}_channel_state;\n\n"
      "/* One axis: its own temperature channel, the channels its grad terms read, the lags. */\n"
      "typedef struct {{\n"
      "  {p}_channel_state temperature;\n"
      "{channel_field}"
      "  int started;\n"
      "  double start_time;\n"
      "  double last_time;\n"
      "  double step_seconds;               /* since the previous sample; 0 at a (re)start */\n"
      "  {p}_real filters[{P}_FILTERS][2];  /* lag states of the feature terms, two per factor */\n"
      "}} {p}_axis_state;\n\n"
      "typedef struct {{\n"
      "  {p}_axis_state axis[{P}_AXES];\n"
      "  {p}_real drift[{P}_AXES];         /* last predicted drift per axis, deg/h */\n"
      "  unsigned long dropped_samples;   /* ring overflows: the device sampled faster than {P}_MAX_RATE_HZ */\n"
      "  unsigned long rejected_samples;  /* samples with a non-finite or implausible input, rejected whole */\n"
      "}} {p}_state;\n\n"
      "typedef struct {{\n"
      "  double smooth_seconds;\n"
      "  double rate_span_seconds;\n"
      "  double gap_seconds;\n"
      "  double warm_up_seconds;\n"
      "  {p}_real reference_temperature;\n"
      "}} {p}_pipeline;\n\n",
      fmt::arg("P", P), fmt::arg("p", p), fmt::arg("axes", axes), fmt::arg("rate", Literal::time(rate)),
      fmt::arg("temperatures", model.temperature_inputs()),
      fmt::arg("channel_field", grad_slots > 0 ? fmt::format("  {}_channel_state channel[{}];  /* read by grad terms */\n",
                                                             p, grad_slots)
                                               : std::string()),
      fmt::arg("mean", mean_capacity), fmt::arg("history", history_capacity),
      fmt::arg("filters", filter_slots(model)), fmt::arg("single", options.single_precision ? 1 : 0),
      fmt::arg("raw", raw ? 1 : 0),
      fmt::arg("carry_field", options.single_precision
                                  ? fmt::format("  {}_real mean_carry;                /* Kahan compensation of mean_sum */\n", p)
                                  : std::string()),
      fmt::arg("real", options.single_precision ? "float" : "double"));

  out += fmt::format("static const {p}_pipeline {p}_pipelines[{P}_AXES] = {{\n", fmt::arg("p", p), fmt::arg("P", P));
  for (std::size_t a = 0; a < axes; ++a) {
    const Pipeline& pipeline = model.axes[a].pipeline;
    out += fmt::format("    {{{}, {}, {}, {}, {}}}{}  /* {} */\n", Literal::time(pipeline.smooth_seconds),
                       Literal::time(pipeline.rate_span_seconds), Literal::time(pipeline.effective_gap_seconds()),
                       Literal::time(pipeline.warm_up_seconds()), literal(pipeline.reference_temperature),
                       a + 1 < axes ? "," : "", comment_safe(model.axes[a].name));
  }
  out += "};\n\n";
  if (raw) append_input_scaling(out, model, p, P);

  if (single) {
    out += fmt::format(
        "/* Compensated (Kahan) summation: *sum + value with the rounding error carried.\n"
        " * Do not compile with -ffast-math, which would optimise the carry away. */\n"
        "static inline void {p}_accumulate({p}_real* sum, {p}_real* carry, {p}_real value) {{\n"
        "  const {p}_real corrected = value - *carry;\n"
        "  const {p}_real total = *sum + corrected;\n"
        "  *carry = (total - *sum) - corrected;\n"
        "  *sum = total;\n"
        "}}\n\n",
        fmt::arg("p", p));
  }

  // A least-squares model as a C function of the features: `prefix` names its arrays.
  auto emit_linear = [&](const LinearModel& linear, const std::string& name, const std::string& function_name,
                         std::size_t d) {
    const std::size_t k_count = linear.regressors.size();
    if (k_count > 0) {
      out += fmt::format("static const {}_real {}_coefficients[{}] = {{", p, name, k_count);
      append_array(out, literal, linear.coefficients.data(), k_count);
      out += "};\n";
      out += fmt::format("/* regressor k = product over terms i of features[i]^powers[k][i] */\n"
                         "static const unsigned char {}_powers[{}][{}] = {{",
                         name, k_count, d);
      for (std::size_t k = 0; k < k_count; ++k) {
        out += fmt::format("\n    {{{}}}{}", fmt::join(linear.regressors[k].powers, ", "), k + 1 < k_count ? "," : "");
      }
      out += "};\n";
    }
    out += fmt::format("static inline {}_real {}(const {}_real features[{}]) {{\n", p, function_name, p, d);
    out += fmt::format("  {}_real value = {};\n", p, literal(linear.intercept));
    if (k_count > 0) {
      out += fmt::format(
          "  int k, i, power;\n"
          "  for (k = 0; k < {k}; ++k) {{\n"
          "    {p}_real regressor = 1;\n"
          "    for (i = 0; i < {d}; ++i) {{\n"
          "      for (power = 0; power < {name}_powers[k][i]; ++power) regressor *= features[i];\n"
          "    }}\n"
          "    value += {name}_coefficients[k] * regressor;\n"
          "  }}\n",
          fmt::arg("p", p), fmt::arg("name", name), fmt::arg("d", d), fmt::arg("k", k_count));
    } else {
      out += "  (void)features;\n";
    }
    out += "  return value;\n}\n\n";
  };

  // One drift function per axis: the model's prediction, term for term as in C++.
  for (std::size_t a = 0; a < axes; ++a) {
    const AxisModel& axis = model.axes[a];
    const std::size_t d = axis.pipeline.terms.size();
    const std::string name = fmt::format("{}_axis{}", p, a);
    out += fmt::format("/* Axis {}: {} ({} model; terms {}). */\n", a, comment_safe(axis.name), axis.kind,
                       fmt::join(axis.pipeline.term_names(), ", "));
    if (const auto* svr = std::get_if<SvrModel>(&axis.model)) {
      if (svr->linear_part) emit_linear(*svr->linear_part, name + "_linear", name + "_linear_part", d);
      const auto& function = svr->function;
      const auto sv = static_cast<std::size_t>(function.support_vectors.rows());
      out += fmt::format("static const {}_real {}_feature_mean[{}] = {{", p, name, d);
      append_array(out, literal, svr->scaling.feature_mean.data(), d);
      out += "};\n";
      out += fmt::format("static const {}_real {}_feature_scale[{}] = {{", p, name, d);
      append_array(out, literal, svr->scaling.feature_scale.data(), d);
      out += "};\n";
      if (sv > 0) {
        out += fmt::format("static const {}_real {}_support_vectors[{}][{}] = {{", p, name, sv, d);
        for (std::size_t k = 0; k < sv; ++k) {
          out += "\n    {";
          for (std::size_t j = 0; j < d; ++j) {
            out += literal(function.support_vectors(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)));
            if (j + 1 < d) out += ", ";
          }
          out += k + 1 < sv ? "}," : "}";
        }
        out += "};\n";
        out += fmt::format("static const {}_real {}_coefficients[{}] = {{", p, name, sv);
        append_array(out, literal, function.coefficients.data(), sv);
        out += "};\n";
      }
      out += fmt::format(
          "static inline {p}_real {name}_drift(const {p}_real features[{d}]) {{\n"
          "  {p}_real x[{d}];\n"
          "  {p}_real sum = {bias};\n"
          "{carry}"
          "  int j;\n"
          "  for (j = 0; j < {d}; ++j) x[j] = (features[j] - {name}_feature_mean[j]) / {name}_feature_scale[j];\n",
          fmt::arg("p", p), fmt::arg("name", name), fmt::arg("d", d), fmt::arg("bias", literal(function.bias)),
          fmt::arg("carry", single && sv > 0 ? fmt::format("  {}_real carry = 0;\n", p) : std::string()));
      if (sv > 0) {
        out += fmt::format(
            "  {{\n"
            "    unsigned long k;\n"
            "    for (k = 0; k < {sv}; ++k) {{\n"
            "      {p}_real squared = 0;\n"
            "      for (j = 0; j < {d}; ++j) {{\n"
            "        const {p}_real difference = {name}_support_vectors[k][j] - x[j];\n"
            "        squared += difference * difference;\n"
            "      }}\n"
            "      {accumulate_term}\n"
            "    }}\n"
            "  }}\n",
            fmt::arg("p", p), fmt::arg("name", name), fmt::arg("d", d), fmt::arg("sv", sv),
            fmt::arg("accumulate_term",
                     accumulate("sum", "carry", fmt::format("{}_coefficients[k] * {}(-{} * squared)", name, exp_name,
                                                            literal(function.gamma)))));
      }
      out += fmt::format("  return sum * {} + {}{};\n}}\n\n", literal(svr->scaling.target_scale),
                         literal(svr->scaling.target_mean),
                         svr->linear_part ? fmt::format(" + {}_linear_part(features)", name) : std::string());
    } else {
      emit_linear(std::get<LinearModel>(axis.model), name, name + "_drift", d);
    }
  }

  // The pipeline: FeatureStream::push, SmoothedChannel::push and TrailingMean::push, step for step.
  out += fmt::format(
      "static inline void {p}_channel_restart({p}_channel_state* channel) {{\n"
      "  channel->mean_head = 0;\n"
      "  channel->mean_count = 0;\n"
      "  channel->mean_sum = 0;\n"
      "{reset_carry}"
      "  channel->pushes_since_resum = 0;\n"
      "  channel->history_head = 0;\n"
      "  channel->history_count = 0;\n"
      "}}\n\n"
      "static inline void {p}_axis_restart({p}_axis_state* axis) {{\n"
      "  {p}_channel_restart(&axis->temperature);\n"
      "{restart_channels}"
      "  axis->started = 0;\n"
      "}}\n\n"
      "/* Resets every axis: call once before the first step (and to restart by hand). */\n"
      "static inline void {p}_init({p}_state* state) {{\n"
      "  int a;\n"
      "  for (a = 0; a < {P}_AXES; ++a) {{\n"
      "    {p}_axis_restart(&state->axis[a]);\n"
      "    state->axis[a].temperature.resum_period = {initial};\n"
      "{init_channels}"
      "    state->axis[a].start_time = 0;\n"
      "    state->axis[a].last_time = 0;\n"
      "    state->drift[a] = 0;\n"
      "  }}\n"
      "  state->dropped_samples = 0;\n"
      "  state->rejected_samples = 0;\n"
      "}}\n\n"
      "/* Pushes one temperature into a channel; writes its mean and rate (degC/min).\n"
      " * Sets *dropped when a full ring had to lose its oldest sample. */\n"
      "static inline void {p}_channel_push({p}_channel_state* channel, const {p}_pipeline* pipeline, double time,\n"
      "                                    {p}_real temperature, {p}_real* smoothed, {p}_real* rate, int* dropped) {{\n"
      "  double elapsed;\n"
      "  const {p}_stamped* past;\n"
      "  {p}_real leaving;\n"
      "  int jump = 0;\n"
      "  /* trailing mean over (t - smooth, t] */\n"
      "  while (channel->mean_count > 0 && channel->mean_ring[channel->mean_head].time <= time - pipeline->smooth_seconds) {{\n"
      "    leaving = channel->mean_ring[channel->mean_head].value;\n"
      "    {subtract_oldest}\n"
      "    channel->mean_head = (channel->mean_head + 1) % {P}_MEAN_CAPACITY;\n"
      "    --channel->mean_count;\n"
      "    {jump}\n"
      "  }}\n"
      "  if (channel->mean_count == channel->resum_period) channel->resum_period *= 2;\n"
      "  if (channel->mean_count == {P}_MEAN_CAPACITY) {{\n"
      "    leaving = channel->mean_ring[channel->mean_head].value;\n"
      "    {subtract_oldest}\n"
      "    channel->mean_head = (channel->mean_head + 1) % {P}_MEAN_CAPACITY;\n"
      "    --channel->mean_count;\n"
      "    {jump}\n"
      "    *dropped = 1;\n"
      "  }}\n"
      "  channel->mean_ring[(channel->mean_head + channel->mean_count) % {P}_MEAN_CAPACITY].time = time;\n"
      "  channel->mean_ring[(channel->mean_head + channel->mean_count) % {P}_MEAN_CAPACITY].value = temperature;\n"
      "  ++channel->mean_count;\n"
      "  {add_temperature}\n"
      "  /* a running sum drifts by rounding; re-adding the window once per period keeps it exact,\n"
      "   * and at once when a value far larger than what stays has left (it took their digits) */\n"
      "  if (++channel->pushes_since_resum >= channel->resum_period || jump) {{\n"
      "    unsigned long i;\n"
      "    channel->mean_sum = 0;\n"
      "{reset_carry_inner}"
      "    for (i = 0; i < channel->mean_count; ++i) {{\n"
      "      {add_entry}\n"
      "    }}\n"
      "    channel->pushes_since_resum = 0;\n"
      "  }}\n"
      "  *smoothed = channel->mean_sum / ({p}_real)channel->mean_count;\n"
      "\n"
      "  /* rate: backward difference to the last kept mean at or before t - span */\n"
      "  if (channel->history_count == {P}_HISTORY_CAPACITY) {{\n"
      "    channel->history_head = (channel->history_head + 1) % {P}_HISTORY_CAPACITY;\n"
      "    --channel->history_count;\n"
      "    *dropped = 1;\n"
      "  }}\n"
      "  channel->history[(channel->history_head + channel->history_count) % {P}_HISTORY_CAPACITY].time = time;\n"
      "  channel->history[(channel->history_head + channel->history_count) % {P}_HISTORY_CAPACITY].value = *smoothed;\n"
      "  ++channel->history_count;\n"
      "  while (channel->history_count >= 2 &&\n"
      "         channel->history[(channel->history_head + 1) % {P}_HISTORY_CAPACITY].time <= time - pipeline->rate_span_seconds) {{\n"
      "    channel->history_head = (channel->history_head + 1) % {P}_HISTORY_CAPACITY;\n"
      "    --channel->history_count;\n"
      "  }}\n"
      "  past = &channel->history[channel->history_head];\n"
      "  elapsed = time - past->time;\n"
      "  *rate = elapsed > 0 ? (*smoothed - past->value) / ({p}_real)elapsed * ({p}_real)60 : ({p}_real)0;\n"
      "}}\n\n"
      "/* Pushes the axis' own temperature (restarting after a gap); writes dT and the rate\n"
      " * (degC/min); returns 1 once warm. */\n"
      "static inline int {p}_axis_push({p}_axis_state* axis, const {p}_pipeline* pipeline, double time,\n"
      "                                 {p}_real temperature, {p}_real* delta_t, {p}_real* rate, int* dropped) {{\n"
      "  {p}_real smoothed;\n"
      "  if (axis->started && (time - axis->last_time > pipeline->gap_seconds || !(time > axis->last_time))) {{\n"
      "    {p}_axis_restart(axis);\n"
      "  }}\n"
      "  axis->step_seconds = axis->started ? time - axis->last_time : 0;\n"
      "  if (!axis->started) {{\n"
      "    axis->started = 1;\n"
      "    axis->start_time = time;\n"
      "  }}\n"
      "  axis->last_time = time;\n"
      "  {p}_channel_push(&axis->temperature, pipeline, time, temperature, &smoothed, rate, dropped);\n"
      "  {delta_t}\n"
      "  return time - axis->start_time >= pipeline->warm_up_seconds;\n"
      "}}\n\n",
      fmt::arg("p", p), fmt::arg("P", P), fmt::arg("initial", kTrailingMeanInitialCapacity),
      fmt::arg("delta_t", single ? "*delta_t = smoothed;  /* the float rings hold T - reference */"
                                 : "*delta_t = smoothed - pipeline->reference_temperature;"),
      fmt::arg("restart_channels",
               grad_slots > 0 ? fmt::format("  {{\n    int c;\n    for (c = 0; c < {}; ++c) {}_channel_restart(&axis->channel[c]);\n  }}\n",
                                            grad_slots, p)
                              : std::string()),
      fmt::arg("init_channels",
               grad_slots > 0 ? fmt::format("    {{\n      int c;\n      for (c = 0; c < {}; ++c) state->axis[a].channel[c].resum_period = {};\n    }}\n",
                                            grad_slots, kTrailingMeanInitialCapacity)
                              : std::string()),
      fmt::arg("reset_carry", single ? "  channel->mean_carry = 0;\n" : ""),
      fmt::arg("reset_carry_inner", single ? "    channel->mean_carry = 0;\n" : ""),
      fmt::arg("subtract_oldest", accumulate("channel->mean_sum", "channel->mean_carry", "-leaving")),
      fmt::arg("jump", fmt::format("if ({fabs}(leaving) > ({p}_real){limit} * ({fabs}(channel->mean_sum) + "
                                   "({p}_real)channel->mean_count)) jump = 1;",
                                   fmt::arg("fabs", single ? "fabsf" : "fabs"), fmt::arg("p", p),
                                   fmt::arg("limit", literal(TrailingMean::kResumJump)))),
      fmt::arg("add_temperature", accumulate("channel->mean_sum", "channel->mean_carry", "temperature")),
      fmt::arg("add_entry", accumulate("channel->mean_sum", "channel->mean_carry",
                                       fmt::format("channel->mean_ring[(channel->mean_head + i) % {}_MEAN_CAPACITY].value", P))));

  // The feature terms' lags: TermEvaluator, operation for operation.
  out += fmt::format(
      "/* First-order lag, exact for an input held over the step; a step of 0 (a restart)\n"
      " * sets the state to the input: the lags start in equilibrium. */\n"
      "static inline {p}_real {p}_lag({p}_real state, {p}_real input, double step_seconds, double tau) {{\n"
      "  {p}_real a;\n"
      "  if (!(step_seconds > 0)) return input;\n"
      "  a = ({p}_real){exp}(-step_seconds / tau);\n"
      "  return a * state + (({p}_real)1 - a) * input;\n"
      "}}\n\n"
      "/* max(0, value): the hinges of a piecewise-linear static map */\n"
      "static inline {p}_real {p}_positive_part({p}_real value) {{\n"
      "  return value > 0 ? value : ({p}_real)0;\n"
      "}}\n\n"
      "/* lagrate:TAU, degC/min: the rate of a TAU-lag of dT (state[0]) */\n"
      "static inline {p}_real {p}_lag_rate({p}_real* lagged, {p}_real delta_t, double step_seconds, double tau) {{\n"
      "  *lagged = {p}_lag(*lagged, delta_t, step_seconds, tau);\n"
      "  return ({p}_real)((delta_t - *lagged) / tau * 60.0);\n"
      "}}\n\n"
      "/* lag2:T1:T2 (what 0), lag2rate:T1:T2 (1, degC/min) and nodehinge:T1:T2:TL:K (2): L1 = a\n"
      " * T1-lag of dT (state[0]), L2 a T2-lag of L1 (state[1]); the node N = L2 + TL dL2/dt, or\n"
      " * L1 + TL dL1/dt when T2 = 0, through max(0, N - K) */\n"
      "static inline {p}_real {p}_node({p}_real state[2], {p}_real delta_t, double step_seconds, double t1,\n"
      "                                double t2, double tl, double knot, int what) {{\n"
      "  double node;\n"
      "  state[0] = {p}_lag(state[0], delta_t, step_seconds, t1);\n"
      "  if (t2 > 0) state[1] = {p}_lag(state[1], state[0], step_seconds, t2);\n"
      "  if (what == 0) return state[1];\n"
      "  if (what == 1) return ({p}_real)((state[0] - state[1]) / t2 * 60.0);\n"
      "  node = t2 > 0 ? state[1] + tl * (state[0] - state[1]) / t2 : state[0] + tl * (delta_t - state[0]) / t1;\n"
      "  return node > knot ? ({p}_real)(node - knot) : ({p}_real)0;\n"
      "}}\n\n"
      "/* play:TAU:W: (L - P)/W, L a TAU-lag of dT (state[0]), P (state[1]) the play operator on L\n"
      " * with half-width W: it moves only to stay within W of L; a restart sets it to L */\n"
      "static inline {p}_real {p}_play({p}_real state[2], {p}_real delta_t, double step_seconds, double tau,\n"
      "                                {p}_real width) {{\n"
      "  state[0] = {p}_lag(state[0], delta_t, step_seconds, tau);\n"
      "  if (!(step_seconds > 0)) state[1] = state[0];\n"
      "  if (state[1] < state[0] - width) state[1] = state[0] - width;\n"
      "  if (state[1] > state[0] + width) state[1] = state[0] + width;\n"
      "  return (state[0] - state[1]) / width;\n"
      "}}\n\n"
      "/* gradrate:TAU:TG, degC/min^2: the rate of a TG-lag (state[1]) of lagrate:TAU */\n"
      "static inline {p}_real {p}_gradient_rate({p}_real state[2], {p}_real delta_t, double step_seconds,\n"
      "                                          double tau, double tau_gradient) {{\n"
      "  const {p}_real coil_rate = {p}_lag_rate(&state[0], delta_t, step_seconds, tau);\n"
      "  state[1] = {p}_lag(state[1], coil_rate, step_seconds, tau_gradient);\n"
      "  return ({p}_real)((coil_rate - state[1]) / tau_gradient * 60.0);\n"
      "}}\n\n"
      "/* dir:TAU[:LAG]: a TAU-lag (state[1]) of tanh(r / {scale} degC/min), tanh through exp;\n"
      " * r is the smoothed rate, or lagrate:LAG when LAG > 0 */\n"
      "static inline {p}_real {p}_direction({p}_real state[2], {p}_real delta_t, {p}_real rate,\n"
      "                                     double step_seconds, double tau, double lag) {{\n"
      "  const double source = lag > 0 ? (double){p}_lag_rate(&state[0], delta_t, step_seconds, lag) : (double)rate;\n"
      "  const double x = source / {scale};\n"
      "  state[1] = {p}_lag(state[1], ({p}_real)(1.0 - 2.0 / (exp(2.0 * x) + 1.0)), step_seconds, tau);\n"
      "  return state[1];\n"
      "}}\n\n",
      fmt::arg("p", p), fmt::arg("exp", exp_name), fmt::arg("scale", Literal::time(kDirectionRateScale)));

  if (raw) {
    out += fmt::format(
        "/* One sample: gyro raw per axis (in {unit} before the scale), temperatures raw (one per\n"
        " * axis, then the extra channels: {P}_TEMPERATURES), as the log holds them; time in s\n"
        " * (increasing). Writes gyro - drift per axis in deg/h to compensated (may alias\n"
        " * gyro_raw); returns 1 when ready. */\n"
        "static inline int {p}_step({p}_state* state, double time, const double gyro_raw[{P}_AXES],\n"
        "                            const double temperature_raw[{P}_TEMPERATURES], double compensated[{P}_AXES]) {{\n"
        "  double gyro[{P}_AXES];\n"
        "  double temperature[{P}_TEMPERATURES];\n"
        "  int ready = 1;\n"
        "  int dropped = 0;\n"
        "  int i;\n"
        "  {p}_real delta_t;\n"
        "  {p}_real rate;\n"
        "  for (i = 0; i < {P}_AXES; ++i) gyro[i] = gyro_raw[i] * {p}_gyro_factor[i];\n"
        "  for (i = 0; i < {P}_TEMPERATURES; ++i) {{\n"
        "    temperature[i] = {p}_temperature_scale[i] * temperature_raw[i] + {p}_temperature_offset[i];\n"
        "  }}\n",
        fmt::arg("p", p), fmt::arg("P", P), fmt::arg("unit", to_string(model.gyro_unit)));
  } else {
    out += fmt::format(
        "/* One sample: gyro in deg/h per axis, temperatures in degC (one per axis, then the\n"
        " * extra channels: {P}_TEMPERATURES), time in s (increasing).\n"
        " * Writes gyro - drift per axis to compensated (may alias gyro); returns 1 when ready. */\n"
        "static inline int {p}_step({p}_state* state, double time, const double gyro[{P}_AXES],\n"
        "                            const double temperature[{P}_TEMPERATURES], double compensated[{P}_AXES]) {{\n"
        "  int ready = 1;\n"
        "  int dropped = 0;\n"
        "  {p}_real delta_t;\n"
        "  {p}_real rate;\n",
        fmt::arg("p", p), fmt::arg("P", P));
  }
  out += fmt::format(
      "  {{\n"
      "    /* false for NaN and infinities too */\n"
      "    int plausible = isfinite(time);\n"
      "    int k;\n"
      "    for (k = 0; k < {P}_AXES; ++k) plausible = plausible && gyro[k] >= {min_rate} && gyro[k] <= {max_rate};\n"
      "    for (k = 0; k < {P}_TEMPERATURES; ++k) {{\n"
      "      plausible = plausible && temperature[k] >= {min_t} && temperature[k] <= {max_t};\n"
      "    }}\n"
      "    if (!plausible) {{  /* a failed read: rejected whole, the state left as it was */\n"
      "      for (k = 0; k < {P}_AXES; ++k) compensated[k] = NAN;\n"
      "      ++state->rejected_samples;\n"
      "      return 0;\n"
      "    }}\n"
      "  }}\n",
      fmt::arg("P", P), fmt::arg("min_rate", Literal(false)(-kMaxRateDph)),
      fmt::arg("max_rate", Literal(false)(kMaxRateDph)), fmt::arg("min_t", Literal(false)(kMinTemperatureC)),
      fmt::arg("max_t", Literal(false)(kMaxTemperatureC)));
  for (std::size_t a = 0; a < axes; ++a) {
    const auto& terms = model.axes[a].pipeline.terms;
    // In float the pipeline runs on T - reference, rounded once from double: smaller
    // numbers, smaller rounding; the mean and the rate are the same quantities.
    auto temperature = [&](std::size_t channel) {
      return single ? fmt::format("({}_real)(temperature[{}] - {})", p, channel,
                                  Literal::time(model.axes[a].pipeline.reference_temperature))
                    : fmt::format("temperature[{}]", channel);
    };
    out += fmt::format(
        "  if (!{p}_axis_push(&state->axis[{a}], &{p}_pipelines[{a}], time, {temperature}, &delta_t, &rate,\n"
        "                   &dropped)) {{\n"
        "    ready = 0;\n"
        "  }}\n"
        "  {{\n"
        "    {p}_real features[{d}];\n",
        fmt::arg("p", p), fmt::arg("a", a), fmt::arg("d", terms.size()), fmt::arg("temperature", temperature(a)));
    // The channels grad terms read: smoothed beside the axis' own, slot by slot.
    const std::vector<std::size_t> channels = model.axes[a].pipeline.channels();
    auto slot_of = [&](std::size_t channel) {
      return static_cast<std::size_t>(std::find(channels.begin(), channels.end(), channel) - channels.begin());
    };
    if (!channels.empty()) {
      out += fmt::format("    {p}_real channel_mean[{n}];\n    {p}_real channel_rate[{n}];\n", fmt::arg("p", p),
                         fmt::arg("n", channels.size()));
      for (std::size_t c = 0; c < channels.size(); ++c) {
        out += fmt::format(
            "    {p}_channel_push(&state->axis[{a}].channel[{c}], &{p}_pipelines[{a}], time, {temperature},\n"
            "                     &channel_mean[{c}], &channel_rate[{c}], &dropped);  /* channel {number} */\n",
            fmt::arg("p", p), fmt::arg("a", a), fmt::arg("c", c), fmt::arg("temperature", temperature(channels[c])),
            fmt::arg("number", channels[c] + 1));
      }
    }
    std::size_t slot = 0;
    for (std::size_t i = 0; i < terms.size(); ++i) {
      out += fmt::format("    features[{}] = 1;\n", i);
      for (const auto& factor : terms[i].factors) {
        const std::string state = fmt::format("state->axis[{}].filters[{}]", a, slot++);
        const std::string step = fmt::format("state->axis[{}].step_seconds", a);
        const FeatureAtom& atom = factor.atom;
        std::string value;
        switch (atom.kind) {
          case FeatureAtom::Kind::delta_t: value = "delta_t"; break;
          case FeatureAtom::Kind::rate: value = "rate"; break;
          case FeatureAtom::Kind::lag:
            out += fmt::format("    {s}[0] = {p}_lag({s}[0], delta_t, {step}, {tau});\n", fmt::arg("s", state),
                               fmt::arg("p", p), fmt::arg("step", step), fmt::arg("tau", Literal::time(atom.tau)));
            value = state + "[0]";
            break;
          case FeatureAtom::Kind::hinge:
            out += fmt::format("    {s}[0] = {p}_lag({s}[0], delta_t, {step}, {tau});\n", fmt::arg("s", state),
                               fmt::arg("p", p), fmt::arg("step", step), fmt::arg("tau", Literal::time(atom.tau)));
            value = fmt::format("({s}[0] > {k} ? {s}[0] - {k} : ({p}_real)0)", fmt::arg("s", state), fmt::arg("p", p),
                                fmt::arg("k", literal(atom.level)));
            break;
          case FeatureAtom::Kind::lead:
            value = fmt::format("(delta_t + {} * rate / ({}_real)60)", literal(atom.tau), p);
            break;
          case FeatureAtom::Kind::lead_hinge:
            value = fmt::format("{p}_positive_part(delta_t + {tau} * rate / ({p}_real)60 - {k})", fmt::arg("p", p),
                                fmt::arg("tau", literal(atom.tau)), fmt::arg("k", literal(atom.level)));
            break;
          case FeatureAtom::Kind::lag2:
          case FeatureAtom::Kind::lag2_rate:
          case FeatureAtom::Kind::node_hinge: {
            const int what = atom.kind == FeatureAtom::Kind::lag2 ? 0 : atom.kind == FeatureAtom::Kind::lag2_rate ? 1 : 2;
            value = fmt::format("{}_node({}, delta_t, {}, {}, {}, {}, {}, {})", p, state, step, Literal::time(atom.tau),
                                atom.tau2 > 0 ? Literal::time(atom.tau2) : std::string("0.0"),
                                atom.zero > 0 ? Literal::time(atom.zero) : std::string("0.0"), literal(atom.level), what);
            break;
          }
          case FeatureAtom::Kind::play:
            value = fmt::format("{}_play({}, delta_t, {}, {}, {})", p, state, step, Literal::time(atom.tau),
                                literal(atom.level));
            break;
          case FeatureAtom::Kind::lag_rate:
            value = fmt::format("{}_lag_rate(&{}[0], delta_t, {}, {})", p, state, step, Literal::time(atom.tau));
            break;
          case FeatureAtom::Kind::gradient_rate:
            value = fmt::format("{}_gradient_rate({}, delta_t, {}, {}, {})", p, state, step, Literal::time(atom.tau),
                                Literal::time(atom.tau2));
            break;
          case FeatureAtom::Kind::direction:
            value = fmt::format("{}_direction({}, delta_t, rate, {}, {}, {})", p, state, step, Literal::time(atom.tau),
                                Literal::time(atom.tau2));
            break;
          case FeatureAtom::Kind::channel_gradient:
            value = fmt::format("(channel_mean[{}] - channel_mean[{}])", slot_of(atom.channel), slot_of(atom.channel2));
            break;
          case FeatureAtom::Kind::channel_gradient_rate:
            value = fmt::format("(channel_rate[{}] - channel_rate[{}])", slot_of(atom.channel), slot_of(atom.channel2));
            break;
          case FeatureAtom::Kind::input: throw UsageError("libsvm columns cannot be exported");  // check_exportable
        }
        if (factor.power == 1) {
          out += fmt::format("    features[{}] *= {};  /* {} */\n", i, value, atom.name());
        } else {
          out += fmt::format("    {{\n      const {}_real v = {};  /* {} */\n", p, value, atom.name());
          for (int k = 0; k < factor.power; ++k) out += fmt::format("      features[{}] *= v;\n", i);
          out += "    }\n";
        }
      }
    }
    out += fmt::format(
        "    state->drift[{a}] = {p}_axis{a}_drift(features);\n"
        "  }}\n"
        "  compensated[{a}] = gyro[{a}] - (double)state->drift[{a}];\n"
        "  if (!isfinite(compensated[{a}])) ready = 0;  /* never a non-finite output flagged valid */\n",
        fmt::arg("p", p), fmt::arg("a", a));
  }
  out += fmt::format(
      "  if (dropped) {{\n"
      "    ++state->dropped_samples;\n"
      "    ready = 0;\n"
      "  }}\n"
      "  return ready;\n"
      "}}\n\n"
      "#ifdef __cplusplus\n}}\n#endif\n\n"
      "#endif /* {P}_H_INCLUDED */\n",
      fmt::arg("P", P));
  return out;
}

}  // namespace thermodrift
