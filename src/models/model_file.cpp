#include "thermodrift/models/model_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>

#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"
#include "thermodrift/io/json_integer.hpp"
#include "thermodrift/io/json_position.hpp"

namespace thermodrift {

namespace {
constexpr const char* kFormatName = "thermodrift-model";

// Every number a model applies — coefficients, scales, support vectors, pipeline and
// envelope values — lies far inside this bound: features are °C, °C/min and s, targets
// °/h below 3.6e8 (kMaxRateDph). A number beyond it is a failed fit or an edited file,
// and would give inf or garbage drift on every sample.
constexpr double kModelNumberLimit = 1e12;

// A model file nests about eight levels deep (axes, an axis, its fit record, ...). Far
// deeper is no model, and the checks below recurse once per level: 30,000 levels of
// arrays overflowed the stack.
constexpr std::size_t kMaxNesting = 100;

// Where `text` first opens an array or object deeper than kMaxNesting, as 1-based line and
// column; nothing if it never does. Brackets inside strings do not count.
std::optional<std::pair<std::size_t, std::size_t>> find_excess_nesting(std::string_view text) {
  std::size_t depth = 0, line = 1, column = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    ++column;
    if (c == '\n') {
      ++line;
      column = 0;
    }
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxNesting) return std::pair{line, column};
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return std::nullopt;
}

// Whether `json` nests deeper than `levels` arrays or objects; recurses at most `levels` deep.
bool nested_deeper_than(const nlohmann::json& json, std::size_t levels) {
  if (!json.is_structured()) return false;
  if (levels == 0) return true;
  return std::any_of(json.begin(), json.end(),
                     [&](const nlohmann::json& value) { return nested_deeper_than(value, levels - 1); });
}

// A number a model cannot apply: what is wrong, and where (a JSON pointer below the value
// searched).
struct BadNumber {
  std::string message;
  std::string pointer;
};

// The first null (JSON's stand-in for NaN and inf) or number beyond the limit in `json`
// but its member `skip`, named by its path ("model.coefficients[1]"); nothing if none.
std::optional<BadNumber> find_bad_number(const nlohmann::json& json, const std::string& path,
                                         std::string_view skip = {}, const std::string& pointer = {}) {
  const std::string& name = path.empty() ? std::string("the file") : path;
  if (json.is_null()) return BadNumber{fmt::format("{} is null, not a finite number", name), pointer};
  if (json.is_number()) {
    const double value = json.get<double>();
    if (!std::isfinite(value)) return BadNumber{fmt::format("{} is not a finite number", name), pointer};
    if (std::abs(value) > kModelNumberLimit) {
      return BadNumber{fmt::format("{} is {:.6g}, beyond the ±{:g} a model's numbers stay within", name, value,
                                   kModelNumberLimit),
                       pointer};
    }
  } else if (json.is_array()) {
    for (std::size_t i = 0; i < json.size(); ++i) {
      if (auto bad = find_bad_number(json[i], fmt::format("{}[{}]", path, i), {}, fmt::format("{}/{}", pointer, i))) {
        return bad;
      }
    }
  } else if (json.is_object()) {
    for (const auto& [key, value] : json.items()) {
      if (path.empty() && key == skip) continue;
      if (auto bad = find_bad_number(value, path.empty() ? key : fmt::format("{}.{}", path, key), {},
                                     json_pointer_child(pointer, key))) {
        return bad;
      }
    }
  }
  return std::nullopt;
}

// e.what() without nlohmann's "[json.exception.type_error.302] " tag: a message for
// people, not a library's error code.
std::string without_json_tag(const std::exception& e) {
  std::string what = e.what();
  if (const auto bracket = what.find("] "); what.starts_with("[json.exception") && bracket != std::string::npos) {
    what.erase(0, bracket + 2);
  }
  return what;
}

// Why reading `json` (at `pointer`) failed with `e`: a number expected but null found is
// named by its path rather than by nlohmann's "type must be number, but is null", and
// `pointer` moves to it.
std::string why_unreadable(const std::exception& e, const nlohmann::json& json, std::string_view skip,
                           std::string& pointer) {
  if (dynamic_cast<const nlohmann::json::type_error*>(&e) != nullptr) {
    if (auto bad = find_bad_number(json, "", skip, pointer)) {
      pointer = bad->pointer;
      return bad->message;
    }
  }
  return without_json_tag(e);
}

// nlohmann keeps the last of repeated keys silently; in a model file a repeated key is
// an edit gone wrong, and which value applies would be a guess.
nlohmann::json parse_without_duplicate_keys(const std::string& text, const std::string& path) {
  std::vector<std::vector<std::string>> open_objects;
  std::string duplicate;
  auto check = [&](int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) {
      open_objects.emplace_back();
    } else if (event == Event::object_end) {
      open_objects.pop_back();
    } else if (event == Event::key && duplicate.empty()) {
      auto& keys = open_objects.back();
      const auto& key = parsed.get_ref<const std::string&>();
      if (std::find(keys.begin(), keys.end(), key) != keys.end()) duplicate = key;
      keys.push_back(key);
    }
    return true;
  };
  nlohmann::json json = nlohmann::json::parse(text, check);
  if (!duplicate.empty()) throw DataError(path, 0, 0, fmt::format("key \"{}\" appears twice in one object", duplicate));
  return json;
}
}  // namespace

double AxisModel::predict(std::span<const double> features) const {
  return std::visit([&](const auto& m) { return m.predict(features); }, model);
}

Eigen::VectorXd AxisModel::predict(const Eigen::MatrixXd& features) const {
  return std::visit([&](const auto& m) { return Eigen::VectorXd(m.predict(features)); }, model);
}

LogSpec DriftModel::log_spec() const {
  LogSpec spec;
  spec.time_column = time_column;
  spec.rate_hz = rate_hz;
  spec.gyro_unit = gyro_unit;
  spec.time_unit = time_unit;
  spec.scaling = scaling;
  spec.despike = despike;
  for (const auto& axis : axes) {
    spec.gyro_columns.push_back(axis.gyro_column);
    spec.temperature_columns.push_back(axis.temperature_column);
  }
  for (const auto& column : extra_temperature_columns) spec.temperature_columns.push_back(column);
  return spec;
}

nlohmann::json to_json(const DriftModel& model) {
  nlohmann::json axes = nlohmann::json::array();
  for (const auto& axis : model.axes) {
    const auto terms = axis.pipeline.term_names();
    nlohmann::json body = std::visit([&](const auto& m) { return m.to_json(terms); }, axis.model);
    nlohmann::json entry = {{"name", axis.name},
                            {"gyro_column", axis.gyro_column},
                            {"temperature_column", axis.temperature_column},
                            {"pipeline", axis.pipeline.to_json()},
                            {"kind", to_string(axis.kind)},
                            {"model", body},
                            {"fit", fit_record_to_json(axis.fit)}};
    if (axis.envelope) entry["training_envelope"] = axis.envelope->to_json();
    axes.push_back(std::move(entry));
  }
  nlohmann::json json = {{"format", kFormatName},
                         {"version", DriftModel::kFormatVersion},
                         {"gyro_unit", std::string(to_string(model.gyro_unit))},
                         {"axes", axes}};
  if (model.time_column) json["time_column"] = *model.time_column;
  // Written only when not the default, so that files of logs in s, °C and °/h stay as they were.
  if (model.time_unit != TimeUnit::s) json["time_unit"] = std::string(to_string(model.time_unit));
  if (!model.scaling.is_default()) {
    json["scaling"] = {{"temperature_scale", model.scaling.temperature_scale},
                       {"temperature_offset", model.scaling.temperature_offset},
                       {"gyro_scale", model.scaling.gyro_scale}};
  }
  if (model.despike) {
    json["despike"] = {{"window", model.despike->window},
                       {"sigmas", model.despike->sigmas},
                       {"replaced_in_training", {{"gyro", model.despiked_gyro}, {"temperature", model.despiked_temperature}}}};
  }
  if (model.rate_hz) json["rate_hz"] = *model.rate_hz;
  if (!model.extra_temperature_columns.empty()) json["extra_temperature_columns"] = model.extra_temperature_columns;
  return json;
}

DriftModel drift_model_from_json(const nlohmann::json& json, const std::string& source,
                                 const JsonPositions* positions) {
  // The value being read, as a JSON pointer: a refusal names its line and column.
  std::string where;
  auto fail = [&](const std::string& what) {
    const TextPosition at = positions != nullptr ? positions->of(where) : TextPosition{0, 0};
    return DataError(source, at.first, at.second, what);
  };
  // Before anything walks it: a JSON value handed in through the API was never scanned.
  if (nested_deeper_than(json, kMaxNesting)) {
    throw fail(fmt::format("arrays or objects nested more than {} deep: not a model file", kMaxNesting));
  }
  try {
    if (!json.is_object() || json.value("format", "") != kFormatName) {
      if (json.is_object() && json.contains("format")) where = "/format";
      throw fail("not a thermodrift model file (no \"format\": \"thermodrift-model\")");
    }
    where = "/version";
    const int version = json_integer<int>(json.at("version"), "version");
    if (version != DriftModel::kFormatVersion) {
      throw fail(fmt::format("model file version {} is not supported (this build reads version {})",
                             version, DriftModel::kFormatVersion));
    }
    DriftModel model;
    where = "/gyro_unit";
    model.gyro_unit = parse_gyro_unit(json.at("gyro_unit").get<std::string>());
    where = "/time_column";
    if (json.contains("time_column")) model.time_column = json.at("time_column").get<std::string>();
    where = "/time_unit";
    if (json.contains("time_unit")) model.time_unit = parse_time_unit(json.at("time_unit").get<std::string>());
    where = "/rate_hz";
    if (json.contains("rate_hz")) {
      model.rate_hz = json.at("rate_hz").get<double>();
      // A row's time is its number over the rate: a subnormal rate made it infinite. (A
      // number beyond the limit, or not finite, is named as such below.)
      if (std::abs(*model.rate_hz) <= kModelNumberLimit && !(*model.rate_hz >= 1 / kModelNumberLimit)) {
        throw fail(fmt::format("rate_hz is {:.6g}: a sampling rate must be at least {:g} Hz", *model.rate_hz,
                               1 / kModelNumberLimit));
      }
    }
    where = "/despike";
    if (json.contains("despike")) {
      const auto& despike = json.at("despike");
      if (!despike.is_object() || !despike.contains("window") || !despike.contains("sigmas")) {
        throw fail("\"despike\" must hold \"window\" and \"sigmas\"");
      }
      DespikeOptions options;
      options.window = json_integer<std::size_t>(despike.at("window"), "despike window");
      if (!despike.at("sigmas").is_number()) throw fail("despike sigmas must be a number");
      options.sigmas = despike.at("sigmas").get<double>();
      std::string why;
      if (!options.IsValid(&why)) throw fail(why);
      model.despike = options;
      if (despike.contains("replaced_in_training")) {
        const auto& replaced = despike.at("replaced_in_training");
        if (!replaced.is_object()) throw fail("despike \"replaced_in_training\" must be an object");
        // Counts, each checked: nlohmann's own conversion of -5.8 to an unsigned is undefined.
        auto counts = [&](const char* key) {
          std::vector<std::size_t> out;
          if (!replaced.contains(key)) return out;
          if (!replaced.at(key).is_array()) throw fail(fmt::format("despike replaced_in_training {} must be a list", key));
          for (const auto& count : replaced.at(key)) {
            out.push_back(json_integer<std::size_t>(count, fmt::format("despike replaced_in_training {}", key)));
          }
          return out;
        };
        model.despiked_gyro = counts("gyro");
        model.despiked_temperature = counts("temperature");
      }
    }
    where = "/extra_temperature_columns";
    if (json.contains("extra_temperature_columns")) {
      model.extra_temperature_columns = json.at("extra_temperature_columns").get<std::vector<std::string>>();
    }
    where = "/axes";
    if (!json.at("axes").is_array() || json.at("axes").empty()) throw fail("model file has no axes");
    where = "/scaling";
    if (json.contains("scaling")) {
      const auto& scaling = json.at("scaling");
      model.scaling.temperature_scale = scaling.value("temperature_scale", std::vector<double>{});
      model.scaling.temperature_offset = scaling.value("temperature_offset", std::vector<double>{});
      model.scaling.gyro_scale = scaling.value("gyro_scale", std::vector<double>{});
      try {
        model.scaling.check(json.at("axes").size(), json.at("axes").size() + model.extra_temperature_columns.size());
      } catch (const UsageError& e) {
        throw fail(fmt::format("scaling: {}", e.what()));
      }
    }
    std::size_t index = 0;
    for (const auto& entry : json.at("axes")) {
      const std::string axis_at = fmt::format("/axes/{}", index);
      // Each part read below moves `where` into it; its own checks name the part.
      auto at = [&](const char* member) -> const nlohmann::json& {
        where = json_pointer_child(axis_at, member);
        return entry.at(member);
      };
      try {
        where = axis_at;
        AxisModel axis;
        axis.name = at("name").get<std::string>();
        axis.gyro_column = at("gyro_column").get<std::string>();
        axis.temperature_column = at("temperature_column").get<std::string>();
        axis.pipeline = Pipeline::from_json(at("pipeline"));
        const auto kind_name = at("kind").get<std::string>();
        const auto kind = model_kind_named(kind_name);
        if (!kind) throw Error(fmt::format("unknown model kind '{}'", excerpt(kind_name)));
        axis.kind = *kind;
        const auto terms = axis.pipeline.term_names();
        if (is_least_squares(axis.kind)) {
          auto linear = LinearModel::from_json(at("model"), terms);
          if (!std::isfinite(linear.intercept) || !linear.coefficients.allFinite()) {
            throw Error("non-finite coefficient");
          }
          axis.model = std::move(linear);
        } else {
          axis.model = SvrModel::from_json(at("model"), terms);
        }
        if (entry.contains("fit")) axis.fit = fit_record_from_json(at("fit"));
        if (entry.contains("training_envelope")) {
          if (axis.pipeline.libsvm) throw Error("a libsvm-format model has no training envelope");
          axis.envelope = TrainingEnvelope::from_json(at("training_envelope"), terms.size());
        }
        where = json_pointer_child(axis_at, "pipeline");
        const std::size_t inputs = json.at("axes").size() + model.extra_temperature_columns.size();
        for (const std::size_t channel : axis.pipeline.channels()) {
          if (channel >= inputs) {
            throw Error(fmt::format("a grad term reads temperature channel {}, but the model has {} temperature "
                                    "input(s)", channel + 1, inputs));
          }
        }
        if (axis.pipeline.temperature_input(0) >= inputs) {
          throw Error(fmt::format("temperature_channel is {}, but the model has {} temperature input(s)",
                                  axis.pipeline.temperature_input(0) + 1, inputs));
        }
        // Whatever the checks above did not read: the fit record is informational.
        if (auto bad = find_bad_number(entry, "", "fit", axis_at)) {
          where = bad->pointer;
          throw Error(bad->message);
        }
        model.axes.push_back(std::move(axis));
      } catch (const DataError&) {
        throw;
      } catch (const std::exception& e) {
        // Named at the part whose reading failed, or at a null or absurd number in the axis.
        std::string bad_at = axis_at;
        const std::string why = why_unreadable(e, entry, "fit", bad_at);
        if (bad_at != axis_at) where = bad_at;
        throw fail(fmt::format("axis {}: {}", index + 1, why));
      }
      ++index;
    }
    if (auto bad = find_bad_number(json, "", "axes")) {
      where = bad->pointer;
      throw Error(bad->message);
    }
    return model;
  } catch (const DataError&) {
    throw;
  } catch (const std::exception& e) {
    std::string bad_at;
    const std::string why = why_unreadable(e, json, "axes", bad_at);
    if (!bad_at.empty()) where = bad_at;
    throw fail(fmt::format("invalid model file: {}", why));
  }
}

void save_drift_model(const DriftModel& model, const std::string& path,
                      const std::vector<std::string>& inputs) {
  AtomicFile out(path, inputs);
  save_drift_model(model, out);
}

void save_drift_model(const DriftModel& model, AtomicFile& out) {
  const std::string text = to_json(model).dump(1) + "\n";
  // What is written must load: a fit that produced NaN or an absurd number stops here.
  try {
    drift_model_from_json(nlohmann::json::parse(text), out.path());
  } catch (const DataError& e) {
    throw Error(fmt::format("{}: the fitted model is not usable, nothing written: {}", out.path(), e.message()));
  }
  out.stream() << text;
  out.commit();
}

DriftModel load_drift_model(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(path, 0, 0, "cannot open the model file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  if (const auto at = find_excess_nesting(text)) {
    throw DataError(path, at->first, at->second,
                    fmt::format("arrays or objects nested more than {} deep: not a model file", kMaxNesting));
  }
  nlohmann::json json;
  try {
    json = parse_without_duplicate_keys(text, path);
  } catch (const nlohmann::json::parse_error& e) {
    // nlohmann's byte count is 1-based: the character it stopped at.
    const TextPosition at = text_position(text, e.byte > 0 ? e.byte - 1 : 0);
    const bool truncated = e.byte >= text.size();
    throw DataError(path, at.first, at.second,
                    truncated ? "model file ends early (truncated?)" : "model file is not valid JSON");
  } catch (const nlohmann::json::exception& e) {
    // A number too large for a double ("1e999") is out_of_range, not a parse_error; it
    // must still be bad data naming the file, not an internal failure.
    throw DataError(path, 0, 0, fmt::format("model file is not valid JSON: {}", without_json_tag(e)));
  }
  try {
    return drift_model_from_json(json, path);
  } catch (const DataError&) {
    // Only a refused file pays for indexing its text: read again, the same refusal comes
    // with the line and column of the value refused.
    const JsonPositions positions(text);
    return drift_model_from_json(json, path, &positions);
  }
}

}  // namespace thermodrift
