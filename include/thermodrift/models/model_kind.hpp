// The kinds of drift model a fit makes, typed: a name only where a person or a file reads
// it (the CLI's --model, the model file's "kind", reports), through to_string and
// parse_model_kind.
#pragma once

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <array>
#include <optional>
#include <string_view>

namespace thermodrift {

enum class ModelKind {
  linear,    // least squares on the terms (models/linear.hpp)
  stepwise,  // least squares on terms chosen by F-tests, squares and products offered
  svr,       // ε-SVR with an RBF kernel (models/svr_model.hpp), C and σ tuned or given
};

inline constexpr std::array<ModelKind, 3> kModelKinds{ModelKind::linear, ModelKind::stepwise, ModelKind::svr};

constexpr std::string_view to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::linear: return "linear";
    case ModelKind::stepwise: return "stepwise";
    case ModelKind::svr: return "svr";
  }
  return "unknown";
}

// The kind a name spells ("linear", "stepwise", "svr"); nothing for any other text.
constexpr std::optional<ModelKind> model_kind_named(std::string_view name) {
  for (ModelKind kind : kModelKinds) {
    if (to_string(kind) == name) return kind;
  }
  return std::nullopt;
}

// In JSON a kind is its name (never the enum's number). Reading one back goes through
// model_kind_named, which refuses an unknown name.
NLOHMANN_JSON_SERIALIZE_ENUM(ModelKind, {{ModelKind::linear, "linear"},
                                         {ModelKind::stepwise, "stepwise"},
                                         {ModelKind::svr, "svr"}})

// Least squares on the terms at the bottom (linear, stepwise): the same model type.
constexpr bool is_least_squares(ModelKind kind) { return kind != ModelKind::svr; }

}  // namespace thermodrift

// fmt::format("{}", kind) writes its name.
template <>
struct fmt::formatter<thermodrift::ModelKind> : fmt::formatter<std::string_view> {
  auto format(thermodrift::ModelKind kind, format_context& context) const {
    return fmt::formatter<std::string_view>::format(thermodrift::to_string(kind), context);
  }
};
