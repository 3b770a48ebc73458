#include "thermodrift/compensate/c_export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>

#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/features/moving_average.hpp"
#include "thermodrift/features/terms.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "compensate/c_export_parts.hpp"
#include "compensate/c_runtime.hpp"
#include "compensate/c_runtime_text.hpp"

namespace thermodrift {

using namespace c_export_detail;

namespace {

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

// The fixed runtime (compensate/c_runtime.c) in the header's names: its prefixes tdrt_
// and TDRT_ become `p`_ and its upper case, and the file's own opening comment (how it is
// built) is left out.
std::string runtime_in(const std::string& p) {
  std::string_view text = kRuntimeSource;
  text.remove_prefix(text.find("*/\n") + 3);
  while (!text.empty() && text.front() == '\n') text.remove_prefix(1);
  const std::string P = upper(p);
  std::string out;
  out.reserve(text.size() + text.size() / 4);
  for (std::size_t at = 0; at < text.size();) {
    if (text.compare(at, 5, "tdrt_") == 0 || text.compare(at, 5, "TDRT_") == 0) {
      out += text[at] == 't' ? p : P;
      out += '_';
      at += 5;
    } else {
      out += text[at++];
    }
  }
  return out;
}

// The statements that set state->drift[a] from the model's prediction: advanced by the
// smoothing window's lag along its slope, as Compensator::push does, operation for
// operation (compensate/compensator.hpp); the prediction itself without smoothing.
std::string drift_at_sample_time(const std::string& p, std::size_t a, const Pipeline& pipeline) {
  const double tau = Compensator::kDriftSlopeFraction * pipeline.smooth_seconds;
  if (!(tau > 0)) return fmt::format("    state->drift[{a}] = {p}_axis{a}_drift(features);\n", fmt::arg("p", p), fmt::arg("a", a));
  return fmt::format(
      "    {{\n"
      "      /* the model predicts the smoothed drift, half the window behind this sample: advanced\n"
      "       * to the sample's time along its slope */\n"
      "      const {p}_real smoothed = {p}_axis{a}_drift(features);\n"
      "      const {p}_channel_state* window = &state->axis[{a}].temperature;\n"
      "      const double step = state->axis[{a}].step_seconds;\n"
      "      const double lead = (time - window->mean_ring[window->mean_head].time) / 2;\n"
      "      if (step > 0) {{  /* a {tau} s lag, exact for a straight line between samples */\n"
      "        const {p}_real decay = ({p}_real){P}_EXP(({p}_real)(-step / {tau}));\n"
      "        state->axis[{a}].trend = decay * state->axis[{a}].trend + (({p}_real)1 - decay) * smoothed +\n"
      "                               (smoothed - state->axis[{a}].smoothed_drift) *\n"
      "                                   (decay - (({p}_real)1 - decay) * ({p}_real)({tau} / step));\n"
      "      }} else {{\n"
      "        state->axis[{a}].trend = smoothed;\n"
      "      }}\n"
      "      state->drift[{a}] = smoothed + ({p}_real)(lead / {tau}) * (smoothed - state->axis[{a}].trend);\n"
      "      state->axis[{a}].smoothed_drift = smoothed;\n"
      "    }}\n",
      fmt::arg("p", p), fmt::arg("P", upper(p)), fmt::arg("a", a), fmt::arg("tau", Literal::time(tau)));
}

}  // namespace

bool CExportOptions::IsValid(std::string* error) const {
  const Invalid fail(error);
  if (!valid_identifier(prefix)) return fail(fmt::format("prefix '{}' is not a C identifier", prefix));
  if (max_rate_hz && !(std::isfinite(*max_rate_hz) && *max_rate_hz > 0)) {
    return fail(fmt::format("--max-rate must be a positive number of hertz, not {}", *max_rate_hz));
  }
  return true;
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
  const RingSizes rings = ring_sizes(model, rate);
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
  out += render(
      kHeaderComment,
      {{"p", p},
       {"source", options.source.empty() ? "" : " from " + comment_safe(options.source)},
       {"exp", exp_name},
       {"state_bytes", exported_state_bytes(model, options)},
       {"units", raw ? fmt::format("time in s; gyro and temperature raw, as the\n"
                                   " * log holds them (gyro in {}; scale and offset applied inside, see\n"
                                   " * {}_gyro_factor and {}_temperature_scale/_offset); compensated rates in deg/h.",
                                   to_string(model.gyro_unit), p, p)
                     : std::string("time in s, gyro rates in deg/h, temperatures in degC.")},
       {"gyro_in", raw ? "gyro_raw" : "gyro_dph"},
       {"temperature_in", raw ? "temperature_raw" : "temperature_c"},
       {"temperatures",
        model.extra_temperature_columns.empty()
            ? std::string("one channel per axis")
            : fmt::format("one channel per axis, then {}",
                          comment_safe(fmt::format("{}", fmt::join(model.extra_temperature_columns, ", "))))},
       {"warm", model.axes.front().pipeline.warm_up_seconds()},
       {"rate", rate},
       {"precision", options.single_precision ? "float" : "double"}});
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
  // The configuration of the fixed runtime (compensate/c_runtime.c), then the runtime in
  // the header's names.
  const auto define = [&](std::string_view name, const auto& value, std::string_view comment = {}) {
    out += fmt::format("#define {}_{} {}{}\n", P, name, value,
                       comment.empty() ? std::string() : fmt::format("  /* {} */", comment));
  };
  define("AXES", axes);
  define("TEMPERATURES", model.temperature_inputs(),
         "temperature inputs: one per axis, then the grad terms' extra channels");
  define("MAX_RATE_HZ", Literal::time(rate));
  define("MEAN_CAPACITY", rings.mean);
  define("HISTORY_CAPACITY", rings.history);
  define("FILTERS", filter_slots(model));
  define("SINGLE_PRECISION", single ? 1 : 0);
  define("RAW_INPUTS", raw ? 1 : 0, "1: step takes gyro and temperature raw, as the log holds them");
  define("GRAD_CHANNELS", grad_slots, "per axis, smoothed for grad terms");
  define("RESUM_INITIAL", kTrailingMeanInitialCapacity);
  define("RESUM_JUMP", literal(TrailingMean::kResumJump));
  out += "\n";
  out += runtime_in(p);

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


  // A least-squares model as a C function of the features: `prefix` names its arrays.
  auto emit_linear = [&](const LinearModel& linear, const std::string& name, const std::string& function_name,
                         std::size_t d) {
    const std::size_t k_count = linear.regressors.size();
    if (k_count > 0) {
      out += fmt::format("static const {}_real {}_coefficients[{}] = {{", p, name, k_count);
      append_array(out, literal, linear.coefficients.data(), k_count);
      out += "};\n";
      out += fmt::format(
          "/* regressor k = product over terms i of features[i]^powers[k][i] */\n"
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
      if (sv == 0) {
        // The kernel left out at fit time (fit.kernel_check): the linear part and a constant.
        out += fmt::format("static inline {p}_real {name}_drift(const {p}_real features[{d}]) {{\n"
                           "{use}  return {bias} * {scale} + {mean}{linear};\n}}\n\n",
                           fmt::arg("p", p), fmt::arg("name", name), fmt::arg("d", d),
                           fmt::arg("use", svr->linear_part ? "" : "  (void)features;\n"),
                           fmt::arg("bias", literal(function.bias)), fmt::arg("scale", literal(svr->scaling.target_scale)),
                           fmt::arg("mean", literal(svr->scaling.target_mean)),
                           fmt::arg("linear", svr->linear_part ? fmt::format(" + {}_linear_part(features)", name)
                                                               : std::string()));
        continue;
      }
      out += fmt::format("static const {}_real {}_feature_mean[{}] = {{", p, name, d);
      append_array(out, literal, svr->scaling.feature_mean.data(), d);
      out += "};\n";
      out += fmt::format("static const {}_real {}_feature_scale[{}] = {{", p, name, d);
      append_array(out, literal, svr->scaling.feature_scale.data(), d);
      out += "};\n";
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
      out += fmt::format(
          "static inline {p}_real {name}_drift(const {p}_real features[{d}]) {{\n"
          "  {p}_real x[{d}];\n"
          "  {p}_real sum = {bias};\n"
          "{carry}"
          "  int j;\n"
          "  for (j = 0; j < {d}; ++j) x[j] = (features[j] - {name}_feature_mean[j]) / {name}_feature_scale[j];\n",
          fmt::arg("p", p), fmt::arg("name", name), fmt::arg("d", d), fmt::arg("bias", literal(function.bias)),
          fmt::arg("carry", single ? fmt::format("  {}_real carry = 0;\n", p) : std::string()));
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
      out += fmt::format("  return sum * {} + {}{};\n}}\n\n", literal(svr->scaling.target_scale),
                         literal(svr->scaling.target_mean),
                         svr->linear_part ? fmt::format(" + {}_linear_part(features)", name) : std::string());
    } else {
      emit_linear(std::get<LinearModel>(axis.model), name, name + "_drift", d);
    }
  }

  if (raw) {
    out += render(kStepRawPrologue, {{"p", p}, {"P", P}, {"unit", to_string(model.gyro_unit)}});
  } else {
    out += render(kStepPrologue, {{"p", p}, {"P", P}});
  }
  out += render(kRejectImplausible, {{"P", P},
                                     {"min_rate", Literal(false)(-kMaxRateDph)},
                                     {"max_rate", Literal(false)(kMaxRateDph)},
                                     {"min_t", Literal(false)(kMinTemperatureC)},
                                     {"max_t", Literal(false)(kMaxTemperatureC)}});
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
        fmt::arg("p", p), fmt::arg("a", a), fmt::arg("d", terms.size()),
        fmt::arg("temperature", temperature(model.axes[a].pipeline.temperature_input(a))));
    // The channels grad terms read: smoothed beside the axis' own, slot by slot.
    const std::vector<std::size_t> channels = model.axes[a].pipeline.channels();
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
        const FactorPlace place{p, fmt::format("state->axis[{}].filters[{}]", a, slot++),
                                fmt::format("state->axis[{}].step_seconds", a), channels, single};
        const FactorCode code = factor_code(factor, place);
        const FeatureAtom& atom = factor.atom;
        const std::string& value = code.value;
        out += code.statements;
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
        "{advance}"
        "  }}\n"
        "  compensated[{a}] = gyro[{a}] - (double)state->drift[{a}];\n"
        "  if (!isfinite(compensated[{a}])) ready = 0;  /* never a non-finite output flagged valid */\n",
        fmt::arg("p", p), fmt::arg("a", a), fmt::arg("advance", drift_at_sample_time(p, a, model.axes[a].pipeline)));
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
