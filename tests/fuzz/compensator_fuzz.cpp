// Any stream of samples through Compensator::push: times that repeat, go back, jump by
// hours or by nanoseconds; NaN, infinities, values at and beyond the physical ranges,
// subnormals. Field code must never flag a non-finite output ready, never read or write
// out of bounds (the sanitizers watch), and count every implausible sample it rejects.
//
// Input: byte 0 picks one of the models fitted once at start-up (the paper's pair with
// linear and SVR, and a linear model on lag, hinge, play, memory and Shupe terms); then
// records of 7 bytes: a time step code, a gyro code per axis (3), a temperature code
// per axis (3).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <vector>

#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/sim/simulator.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace {

using thermodrift::DriftModel;

std::vector<DriftModel>& models() {
  static std::vector<DriftModel> fitted;
  return fitted;
}

DriftModel fit(const thermodrift::ChamberLog& log, thermodrift::ModelKind model, std::vector<std::string> terms) {
  thermodrift::CalibrationOptions options;
  options.model = model;
  options.terms = std::move(terms);
  options.svr.C = 10;
  options.svr.gamma = 0.5;
  return thermodrift::calibrate({log}, {}, options).model;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// A value from a code: mostly plausible readings around `centre`, else a special value.
double value(std::uint8_t code, double centre, double step, double high, double low) {
  switch (code) {
    case 0: return kNaN;
    case 1: return kInf;
    case 2: return -kInf;
    case 3: return 1e300;
    case 4: return -1e300;
    case 5: return high;                            // at the edge of the range: a reading
    case 6: return low;
    case 7: return std::nextafter(high, kInf);      // just beyond it: rejected
    case 8: return std::nextafter(low, -kInf);
    case 9: return std::numeric_limits<double>::denorm_min();
    default: return centre + step * (static_cast<double>(code) - 128.0);
  }
}

// A time step from a code: the usual 1 s, bursts, repeats, steps back, gaps.
double time_step(std::uint8_t code) {
  switch (code) {
    case 0: return 0;      // a repeated stamp
    case 1: return -1;     // the clock went back
    case 2: return 3600;   // a gap of an hour
    case 3: return 1e-9;   // faster than any ring is sized for
    case 4: return 1e9;
    default: return 0.1 * static_cast<double>(code % 20) + 0.05;
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  thermodrift::sim::SimulatorOptions simulation;
  simulation.cycles = 1;
  simulation.rate_hz = 0.2;  // a short log: start-up stays fast under the sanitizers
  const thermodrift::ChamberLog log = thermodrift::sim::to_chamber_log(thermodrift::sim::simulate(simulation));
  models().push_back(fit(log, thermodrift::ModelKind::linear, {"dT", "rate"}));
  models().push_back(fit(log, thermodrift::ModelKind::svr, {"dT", "rate"}));
  models().push_back(fit(log, thermodrift::ModelKind::linear,
                         {"lag:600", "hinge:600:0", "lagrate:600", "rate", "play:600:1", "dir:900:600",
                          "gradrate:600:120", "dT^2", "on:600"}));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  thermodrift::Compensator compensator(models()[data[0] % models().size()]);
  const std::size_t axes = compensator.model().axes.size();
  const std::size_t temperatures = compensator.model().temperature_inputs();
  double time = 0;
  std::size_t implausible = 0;
  std::vector<double> gyro(axes), temperature(temperatures);
  for (std::size_t at = 1; at + 7 <= size; at += 7) {
    // A NaN stamp is one failed read, not a clock that stays NaN.
    const double stamp = data[at] == 5 ? kNaN : (time += time_step(data[at]));
    bool plausible = std::isfinite(stamp);
    for (std::size_t a = 0; a < axes; ++a) {
      gyro[a] = value(data[at + 1 + a % 3], 5.0, 0.5, thermodrift::kMaxRateDph, -thermodrift::kMaxRateDph);
      plausible = plausible && thermodrift::plausible_rate(gyro[a]);
    }
    for (std::size_t c = 0; c < temperatures; ++c) {
      temperature[c] = value(data[at + 4 + c % 3], 20.0, 0.4, thermodrift::kMaxTemperatureC,
                             thermodrift::kMinTemperatureC);
      plausible = plausible && thermodrift::plausible_temperature(temperature[c]);
    }
    if (!plausible) ++implausible;
    const auto& output = compensator.push(stamp, gyro, temperature);
    bool all_ready = true;
    for (std::size_t a = 0; a < axes; ++a) {
      if (output.axes[a].ready && !(std::isfinite(output.compensated[a]) && std::isfinite(output.drift[a]))) {
        std::abort();  // a non-finite value flagged valid
      }
      all_ready = all_ready && output.axes[a].ready;
    }
    if (output.ready != all_ready || (!plausible && output.ready)) std::abort();
  }
  if (compensator.rejected() != implausible) std::abort();
  return 0;
}
