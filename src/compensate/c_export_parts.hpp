// What the parts of the C export share (internal to the compensate module): the export
// is in three files, each with one job —
//   c_export.cpp        the header: declarations, the model's constants, the step function;
//   c_export_terms.cpp  each feature factor as C, and what it costs per sample: the one
//                       place that knows the feature kinds on the export's side;
//   c_export_size.cpp   ring sizes, the state's bytes and the cost model `export` prints;
// and c_runtime.hpp holds the fixed C the header carries (the pipeline and the filters).
#pragma once

#include <fmt/format.h>

#include <cstddef>
#include <string>

#include "thermodrift/compensate/c_export.hpp"
#include "thermodrift/features/terms.hpp"
#include "thermodrift/models/model_file.hpp"

namespace thermodrift::c_export_detail {

// The C++ TrailingMean starts with room for 16 samples and doubles; its exact re-sum
// runs every `ring size` pushes. The header mirrors that period (not the allocation) so
// that both round the same way.
inline constexpr std::size_t kTrailingMeanInitialCapacity = 16;

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
  static std::string time(double value) { return Literal(false)(value); }

 private:
  bool single_;
};

// Filter states per axis in the exported state: two per factor (see TermEvaluator).
std::size_t filter_slots(const DriftModel& model);
// Temperature channels per axis smoothed for grad terms (the most any axis reads).
std::size_t grad_channel_slots(const DriftModel& model);

// The ring capacities of the exported state: the largest any axis needs.
struct RingSizes {
  std::size_t mean = 0;
  std::size_t history = 0;
};
RingSizes ring_sizes(const DriftModel& model, double max_rate_hz);

// Where a factor's C reads from and writes to, for one axis of the header.
struct FactorPlace {
  std::string prefix;            // of the C identifiers
  std::string state;             // its two filter slots, e.g. state->axis[0].filters[3]
  std::string step;              // the axis' step in seconds
  std::vector<std::size_t> channels;  // the axis' grad channels (pipeline.channels())
  bool single_precision = false;
};

// One feature factor in C: statements that advance its filters (may be empty), the
// expression of its value, and its cost per sample.
struct FactorCode {
  std::string statements;
  std::string value;
  std::size_t exps = 0;   // calls of exp
  std::size_t flops = 0;  // other arithmetic, the power included
};
FactorCode factor_code(const FeatureFactor& factor, const FactorPlace& place);

}  // namespace thermodrift::c_export_detail
