// What an exported model costs: ring sizes, the state's bytes, and the cost model
// `export` (and `fit`) print.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "compensate/c_export_parts.hpp"
#include "thermodrift/compensate/c_export.hpp"
#include "thermodrift/error.hpp"

namespace thermodrift {

namespace {

// A state larger than this is a wrong --max-rate, not a device.
constexpr double kMaxRingEntries = 1e8;
constexpr double kDefaultMaxRateHz = 100;

std::size_t ring_capacity(double seconds, double max_rate_hz, std::size_t extra) {
  const double entries = std::ceil(seconds * max_rate_hz) + static_cast<double>(extra);
  if (!(entries <= kMaxRingEntries)) {
    throw UsageError(fmt::format("{} s at {} Hz needs {} ring entries per axis; lower --max-rate",
                                 seconds, max_rate_hz, entries));
  }
  return static_cast<std::size_t>(entries);
}

// Additions and multiplications of a least-squares model's regressors: each power a
// multiply, then a multiply-add per regressor.
std::size_t linear_flops(const LinearModel& linear) {
  std::size_t flops = 0;
  for (const auto& regressor : linear.regressors) {
    flops += static_cast<std::size_t>(std::accumulate(regressor.powers.begin(), regressor.powers.end(), 0)) + 2;
  }
  return flops;
}

// Its constants: coefficients and intercept, and the powers as bytes.
std::size_t linear_bytes(const LinearModel& linear, std::size_t features, std::size_t real) {
  return (linear.regressors.size() + 1) * real + linear.regressors.size() * features;
}

}  // namespace

namespace c_export_detail {

std::size_t filter_slots(const DriftModel& model) {
  std::size_t slots = 1;
  for (const auto& axis : model.axes) {
    std::size_t factors = 0;
    for (const auto& term : axis.pipeline.terms) factors += term.factors.size();
    slots = std::max(slots, factors);
  }
  return slots;
}

std::size_t grad_channel_slots(const DriftModel& model) {
  std::size_t slots = 0;
  for (const auto& axis : model.axes) slots = std::max(slots, axis.pipeline.channels().size());
  return slots;
}

RingSizes ring_sizes(const DriftModel& model, double max_rate_hz) {
  RingSizes sizes;
  for (const auto& axis : model.axes) {
    sizes.mean = std::max(sizes.mean, mean_ring_capacity(axis.pipeline, max_rate_hz));
    sizes.history = std::max(sizes.history, history_ring_capacity(axis.pipeline, max_rate_hz));
  }
  return sizes;
}

}  // namespace c_export_detail

double export_max_rate_hz(const DriftModel& model, const CExportOptions& options) {
  if (options.max_rate_hz) return *options.max_rate_hz;
  if (model.rate_hz && *model.rate_hz > 0) return *model.rate_hz;
  return kDefaultMaxRateHz;
}

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
    const std::size_t count = axis.kind == ModelKind::svr ? axis.support_vectors : axis.regressors;
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
  // The drift at the sample's time (drift_at_sample_time in c_export.cpp): the window's lag
  // (2), the slope's lag of the prediction (10 and an exp) and the advance itself (4).
  constexpr std::size_t kAdvanceFlops = 16;
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
    const c_export_detail::FactorPlace place{"p", "s", "step", axis_model.pipeline.channels(), single_precision};
    axis.flops_per_sample = kPipelineFlops * (1 + place.channels.size());
    if (axis_model.pipeline.smooth_seconds > 0) {  // the drift advanced to the sample's time
      axis.flops_per_sample += kAdvanceFlops;
      axis.exp_per_sample += 1;
    }
    for (const auto& term : axis_model.pipeline.terms) {
      for (const auto& factor : term.factors) {
        const auto code = c_export_detail::factor_code(factor, place);
        axis.exp_per_sample += code.exps;
        axis.flops_per_sample += code.flops;
      }
    }
    if (const auto* svr = std::get_if<SvrModel>(&axis_model.model)) {
      const auto sv = static_cast<std::size_t>(svr->function.support_vectors.rows());
      axis.support_vectors = sv;
      // support vectors, coefficients, feature mean and scale, bias, gamma, target mean and
      // scale; without vectors (the kernel left out at fit time) bias, target mean and scale
      axis.constant_bytes += (sv > 0 ? sv * d + sv + 2 * d + 4 : 3) * real;
      // standardize (2d), per SV: d subtractions, d multiplies, d additions, -γ·s, c·e^…, sum;
      // un-standardize (2)
      axis.flops_per_sample += (sv > 0 ? 2 * d + sv * (3 * d + 3) : 0) + 2;
      axis.exp_per_sample += sv;
      if (svr->linear_part) {
        axis.regressors = svr->linear_part->regressors.size();
        axis.constant_bytes += linear_bytes(*svr->linear_part, d, real);
        axis.flops_per_sample += linear_flops(*svr->linear_part);
      }
    } else if (const auto* linear = std::get_if<LinearModel>(&axis_model.model)) {
      axis.regressors = linear->regressors.size();
      axis.constant_bytes += linear_bytes(*linear, d, real);
      axis.flops_per_sample += linear_flops(*linear);
    }
    size.axes.push_back(axis);
  }
  return size;
}

std::size_t exported_state_bytes(const DriftModel& model, const CExportOptions& options) {
  const auto rings = c_export_detail::ring_sizes(model, export_max_rate_hz(model, options));
  // A ring entry is a double time and a value (padded to 16 bytes in both precisions on
  // common ABIs); a few counters and times per axis.
  const std::size_t entry = 16;
  const std::size_t real = options.single_precision ? sizeof(float) : sizeof(double);
  const std::size_t channels = 1 + c_export_detail::grad_channel_slots(model);
  return model.axes.size() *
         (channels * ((rings.mean + rings.history) * entry + 48) + 2 * c_export_detail::filter_slots(model) * real + 56);
}

}  // namespace thermodrift
