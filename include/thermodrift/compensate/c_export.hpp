// Export of a drift model as one dependency-free C99 header for the navigation
// computer: the model's constants as `static const` arrays, a state struct the caller
// owns (fixed-size ring buffers, no allocation), `<prefix>_init` and `<prefix>_step`
// with the same warm-up and gap rules as FeatureStream, so the device computes what
// `thermodrift compensate` computes. The API of the header is in docs/export.md.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "thermodrift/models/model_file.hpp"

namespace thermodrift {

struct CExportOptions {
  bool single_precision = false;     // float constants and arithmetic (expf); time stamps stay double
  std::string prefix = "thermodrift";  // prefix of every C identifier; upper-cased for macros
  std::optional<double> max_rate_hz;   // sizes the ring buffers; default: the model's rate, else 100 Hz
  std::string source;                // model file name, quoted in the header's comment (informational)

  // True when every field is usable; otherwise false with a one-line reason in *error.
  bool IsValid(std::string* error) const;
};

// The maximum sample rate the ring buffers are sized for (options, model, 100 Hz).
double export_max_rate_hz(const DriftModel& model, const CExportOptions& options);

// Ring capacities the exported state uses for one axis's pipeline at `max_rate_hz`:
// the trailing mean holds the samples of (t - W, t], the rate history the samples of
// [last at or before t - span, t] plus the one being added.
std::size_t mean_ring_capacity(const Pipeline& pipeline, double max_rate_hz);
std::size_t history_ring_capacity(const Pipeline& pipeline, double max_rate_hz);

// What a model costs at prediction time: the figures `export` prints (and `fit` can).
struct ModelSize {
  struct Axis {
    std::string name;
    ModelKind kind = ModelKind::linear;
    std::size_t features = 0;          // pipeline terms (d)
    std::size_t support_vectors = 0;   // SVR only
    std::size_t regressors = 0;        // linear/stepwise only
    std::size_t constant_bytes = 0;    // model constants in the exported header
    std::size_t flops_per_sample = 0;  // additions, subtractions, multiplications, divisions
    std::size_t exp_per_sample = 0;    // calls of exp (one per support vector)
  };
  std::vector<Axis> axes;
  bool single_precision = false;

  std::size_t constant_bytes() const;
  std::size_t flops_per_sample() const;
  std::size_t exp_per_sample() const;
  // Operations per sample counting one exp as one operation (the estimate:
  // per SV d subtractions, d multiplies, d additions, 1 exp, 1 multiply-add).
  std::size_t operations_per_sample() const { return flops_per_sample() + exp_per_sample(); }

  std::string table() const;  // one line per axis and a total line, for the terminal
};

// Prediction cost of `model` (constants counted as float when single_precision).
// Pipeline arithmetic (mean, rate) is included in flops; the state is not a constant.
ModelSize model_size(const DriftModel& model, bool single_precision = false);

// Bytes of the exported state struct (ring buffers of every axis) at options' max rate.
std::size_t exported_state_bytes(const DriftModel& model, const CExportOptions& options);

// The C99 header. Throws UsageError when the options are invalid or the model cannot
// run on a device (a model fitted on libsvm-format data has no pipeline).
std::string export_c_header(const DriftModel& model, const CExportOptions& options = {});

}  // namespace thermodrift
