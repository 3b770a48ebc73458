// Any bytes as a model file: a model that predicts a finite number for a finite
// sample, or a typed error.
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "thermodrift/error.hpp"
#include "thermodrift/models/model_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto json = nlohmann::json::parse(data, data + size, nullptr, false);
  if (json.is_discarded()) return 0;
  try {
    const auto model = thermodrift::drift_model_from_json(json, "fuzz.json");
    for (const auto& axis : model.axes) {
      const std::vector<double> features(axis.pipeline.terms.size(), 0.5);
      const double drift = axis.predict(features);
      // Finite parameters can still overflow (exp of a huge gamma is 0, a huge coefficient
      // times a huge power is inf): only NaN from finite input would be a loader bug.
      if (std::isnan(drift) && axis.kind != thermodrift::ModelKind::svr) std::abort();
    }
  } catch (const thermodrift::Error&) {
  }
  return 0;
}
