#include "thermodrift/models/fit_record.hpp"

#include <fmt/format.h>

#include <limits>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>

#include "thermodrift/error.hpp"
#include "thermodrift/io/json_integer.hpp"

namespace thermodrift {

namespace {

using nlohmann::json;

// Each record's JSON keys, once: a key and the member it holds. Writing and reading both
// walk these lists, so a key is spelled in one place. Members not listed (the tuning box,
// the flags written only when set) go through write_extra / Reader::read_extra.
template <class R, class T>
struct Field {
  const char* key;
  T R::*member;
};
template <class R, class T>
Field(const char*, T R::*) -> Field<R, T>;

template <class R>
struct Fields;  // Fields<R>::list: a tuple of Field<R, ·>

template <>
struct Fields<SvrParameters> {
  static constexpr auto list = std::tuple{Field{"C", &SvrParameters::C}, Field{"sigma", &SvrParameters::sigma},
                                          Field{"gamma", &SvrParameters::gamma},
                                          Field{"epsilon", &SvrParameters::epsilon}};
};
template <>
struct Fields<TuningPoint> {
  static constexpr auto list =
      std::tuple{Field{"evaluations", &TuningPoint::evaluations}, Field{"best_value", &TuningPoint::best_value}};
};
template <>
struct Fields<TuningRecord> {
  static constexpr auto list = std::tuple{
      Field{"method", &TuningRecord::method},        Field{"objective", &TuningRecord::objective},
      Field{"optimistic", &TuningRecord::optimistic}, Field{"folds", &TuningRecord::folds},
      Field{"folds_by", &TuningRecord::folds_by},    Field{"objective_mse", &TuningRecord::objective_mse},
      Field{"fits", &TuningRecord::fits},            Field{"capped_fits", &TuningRecord::capped_fits},
      Field{"seed", &TuningRecord::seed},            Field{"history", &TuningRecord::history}};
};
template <>
struct Fields<KernelCheckRecord> {
  static constexpr auto list = std::tuple{
      Field{"folds", &KernelCheckRecord::folds},
      Field{"folds_by", &KernelCheckRecord::folds_by},
      Field{"with_kernel_mse", &KernelCheckRecord::with_kernel_mse},
      Field{"linear_part_mse", &KernelCheckRecord::linear_part_mse},
      Field{"min_gain", &KernelCheckRecord::min_gain},
      Field{"kept", &KernelCheckRecord::kept}};
};
template <>
struct Fields<SolverRecord> {
  static constexpr auto list = std::tuple{
      Field{"termination", &SolverRecord::termination},
      Field{"iterations", &SolverRecord::iterations},
      Field{"support_vectors", &SolverRecord::support_vectors},
      Field{"dual_objective", &SolverRecord::dual_objective},
      Field{"kernel", &SolverRecord::kernel},
      Field{"landmarks", &SolverRecord::landmarks},
      Field{"mean_kernel_residual", &SolverRecord::mean_kernel_residual},
      Field{"samples_outside_tube", &SolverRecord::samples_outside_tube}};
};
template <>
struct Fields<CompressionRecord> {
  static constexpr auto list = std::tuple{
      Field{"method", &CompressionRecord::method},
      Field{"from_vectors", &CompressionRecord::from_vectors},
      Field{"to_vectors", &CompressionRecord::to_vectors},
      Field{"points", &CompressionRecord::points},
      Field{"rms_change", &CompressionRecord::rms_change},
      Field{"max_change", &CompressionRecord::max_change},
      Field{"unit", &CompressionRecord::unit},
      Field{"training_mse_before", &CompressionRecord::training_mse_before},
      Field{"training_mse_after", &CompressionRecord::training_mse_after},
      Field{"data_mse_before", &CompressionRecord::data_mse_before},
      Field{"data_mse_after", &CompressionRecord::data_mse_after},
      Field{"data", &CompressionRecord::data},
      Field{"settle_seconds", &CompressionRecord::settle_seconds}};
};
template <>
struct Fields<SelectionStepRecord> {
  static constexpr auto list =
      std::tuple{Field{"action", &SelectionStepRecord::action}, Field{"term", &SelectionStepRecord::term},
                 Field{"cv_mse", &SelectionStepRecord::cv_mse}, Field{"terms", &SelectionStepRecord::terms}};
};
template <>
struct Fields<SelectionRecord> {
  static constexpr auto list = std::tuple{
      Field{"method", &SelectionRecord::method},
      Field{"scored_by", &SelectionRecord::scored_by},
      Field{"folds", &SelectionRecord::folds},
      Field{"folds_by", &SelectionRecord::folds_by},
      Field{"min_gain", &SelectionRecord::min_gain},
      Field{"start_mse", &SelectionRecord::start_mse},
      Field{"cv_mse", &SelectionRecord::cv_mse},
      Field{"candidates_scored", &SelectionRecord::candidates_scored},
      Field{"terms", &SelectionRecord::terms},
      Field{"path", &SelectionRecord::path},
      Field{"temperature_channel", &SelectionRecord::temperature_channel},
      Field{"power_on_start", &SelectionRecord::power_on_start},
      Field{"node_under_dynamics", &SelectionRecord::node_under_dynamics},
      Field{"cv_score", &SelectionRecord::cv_score}};
};
template <>
struct Fields<StepwiseStepRecord> {
  static constexpr auto list =
      std::tuple{Field{"action", &StepwiseStepRecord::action}, Field{"regressor", &StepwiseStepRecord::regressor},
                 Field{"F", &StepwiseStepRecord::F}};
};
template <>
struct Fields<ResidualMetrics> {
  static constexpr auto list = std::tuple{
      Field{"samples", &ResidualMetrics::samples},       Field{"mse_before", &ResidualMetrics::mse_before},
      Field{"mse_after", &ResidualMetrics::mse_after},   Field{"residual_std", &ResidualMetrics::residual_std},
      Field{"residual_peak_to_peak", &ResidualMetrics::residual_peak_to_peak}};
};
template <>
struct Fields<FitRecord> {
  static constexpr auto list = std::tuple{
      Field{"terms", &FitRecord::terms},
      Field{"params", &FitRecord::params},
      Field{"standardized", &FitRecord::standardized},
      Field{"tuning", &FitRecord::tuning},
      Field{"solver", &FitRecord::solver},
      Field{"evaluations", &FitRecord::evaluations},
      Field{"compressed", &FitRecord::compressed},
      Field{"kernel_check", &FitRecord::kernel_check},
      Field{"feature_selection", &FitRecord::feature_selection},
      Field{"training_samples", &FitRecord::training_samples},
      Field{"in_sample", &FitRecord::in_sample}};
};

template <class T>
concept Record = requires { Fields<T>::list; };

template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

// ---- writing ----

template <Record R>
json write_record(const R& record);

// What a record writes beyond its field list: nothing, or what its overload adds.
template <class R>
void write_extra(json&, const R&) {}
void write_extra(json& out, const TuningRecord& record);
void write_extra(json& out, const CompressionRecord& record);
void write_extra(json& out, const FitRecord& record);

template <class T>
json write_value(const T& value) {
  if constexpr (Record<T>) {
    return write_record(value);
  } else if constexpr (IsVector<T>::value) {
    json array = json::array();
    for (const auto& item : value) array.push_back(write_value(item));
    return array;
  } else {
    return json(value);
  }
}

template <Record R>
json write_record(const R& record) {
  json out = json::object();
  std::apply(
      [&](const auto&... field) {
        const auto write = [&](const auto& f) {
          const auto& value = record.*(f.member);
          if constexpr (IsOptional<std::remove_cvref_t<decltype(value)>>::value) {
            if (value) out[f.key] = write_value(*value);  // absent, not null
          } else {
            out[f.key] = write_value(value);
          }
        };
        (write(field), ...);
      },
      Fields<R>::list);
  write_extra(out, record);
  return out;
}

void write_extra(json& out, const TuningRecord& record) {
  out["objective_unit"] = "(deg/h)^2";
  out["box"] = {{"C", record.C_box},
                {"sigma", record.sigma_box},
                {"epsilon", record.epsilon_box ? json(*record.epsilon_box) : json(record.epsilon)}};
}

void write_extra(json& out, const CompressionRecord& record) {
  if (record.training_mse_before || record.training_mse_after) out["training_mse_unit"] = "(deg/h)^2";
}

// The flags are written only when set, the stepwise path only when there is one.
void write_extra(json& out, const FitRecord& record) {
  if (record.averaged_linear_part) out["averaged_linear_part"] = true;
  if (record.partially_linear) out["partially_linear"] = true;
  if (!record.stepwise_path.empty()) out["stepwise_path"] = write_value(record.stepwise_path);
}

// ---- reading ----

// One JSON object of the record; `where` names it in errors ("fit.tuning").
class Reader {
 public:
  Reader(const json& object, std::string where) : object_(object), where_(std::move(where)) {
    if (!object_.is_object()) throw Error(fmt::format("{} must be an object", where_));
  }

  const json* find(std::string_view key) const {
    const auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  std::string name(std::string_view key) const { return fmt::format("{}.{}", where_, key); }

  // A number; null (a non-finite value as JSON writes it) reads as NaN.
  static double number(const json& value, const std::string& name) {
    if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (!value.is_number()) throw Error(fmt::format("{} must be a number, not {}", name, value.type_name()));
    return value.get<double>();
  }
  static std::array<double, 2> pair(const json& value, const std::string& name) {
    if (!value.is_array() || value.size() != 2) throw Error(fmt::format("{} must be [low, high]", name));
    return {number(value[0], name), number(value[1], name)};
  }

  template <class T>
  static T value(const json& value, const std::string& name) {
    if constexpr (Record<T>) {
      return read_record<T>(Reader(value, name));
    } else if constexpr (IsVector<T>::value) {
      if (!value.is_array()) throw Error(fmt::format("{} must be an array", name));
      T out;
      for (std::size_t i = 0; i < value.size(); ++i) {
        out.push_back(Reader::value<typename T::value_type>(value[i], fmt::format("{}[{}]", name, i)));
      }
      return out;
    } else if constexpr (std::is_same_v<T, bool>) {
      if (!value.is_boolean()) throw Error(fmt::format("{} must be true or false, not {}", name, value.type_name()));
      return value.get<bool>();
    } else if constexpr (std::is_integral_v<T>) {
      return json_integer<T>(value, name);
    } else if constexpr (std::is_same_v<T, double>) {
      return number(value, name);
    } else {
      static_assert(std::is_same_v<T, std::string>);
      if (!value.is_string()) throw Error(fmt::format("{} must be a string, not {}", name, value.type_name()));
      return value.get<std::string>();
    }
  }

  // Reads `key` into `out` when present; `out` keeps its default otherwise.
  template <class T>
  void read(std::string_view key, T& out) const {
    const json* v = find(key);
    if (v == nullptr) return;
    if constexpr (IsOptional<T>::value) {
      out = value<typename T::value_type>(*v, name(key));
    } else {
      out = value<T>(*v, name(key));
    }
  }

  template <Record R>
  static R read_record(const Reader& reader) {
    R record;
    std::apply([&](const auto&... field) { (reader.read(field.key, record.*(field.member)), ...); }, Fields<R>::list);
    read_extra(reader, record);
    return record;
  }

 private:
  // What a record reads beyond its field list (write_extra's counterparts).
  template <class R>
  static void read_extra(const Reader&, R&) {}
  static void read_extra(const Reader& reader, FitRecord& record) {
    reader.read("averaged_linear_part", record.averaged_linear_part);
    reader.read("partially_linear", record.partially_linear);
    reader.read("stepwise_path", record.stepwise_path);
  }
  static void read_extra(const Reader& reader, TuningRecord& tuning) {
    const json* box = reader.find("box");
    if (box == nullptr) return;
    const Reader fields(*box, reader.name("box"));
    if (const json* C = fields.find("C")) tuning.C_box = pair(*C, fields.name("C"));
    if (const json* sigma = fields.find("sigma")) tuning.sigma_box = pair(*sigma, fields.name("sigma"));
    if (const json* epsilon = fields.find("epsilon")) {
      if (epsilon->is_array()) {
        tuning.epsilon_box = pair(*epsilon, fields.name("epsilon"));
      } else {
        tuning.epsilon = number(*epsilon, fields.name("epsilon"));
      }
    }
  }

  const json& object_;
  std::string where_;
};

}  // namespace

json to_json(const SvrParameters& params) { return write_record(params); }
json to_json(const SolverRecord& record) { return write_record(record); }
json to_json(const SelectionRecord& record) { return write_record(record); }
json to_json(const TuningRecord& record) { return write_record(record); }
json to_json(const CompressionRecord& record) { return write_record(record); }
json to_json(const KernelCheckRecord& record) { return write_record(record); }
json fit_record_to_json(const FitRecord& record) { return write_record(record); }

FitRecord fit_record_from_json(const json& object) { return Reader::read_record<FitRecord>(Reader(object, "fit")); }

}  // namespace thermodrift
