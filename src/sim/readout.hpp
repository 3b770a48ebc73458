// What both simulators' units put out, as a real test records it: a gyro's pulse output
// in whole angle quanta, and a thermometer's reading at its resolution.
#pragma once

#include <cmath>

namespace thermodrift::sim {

// A pulse output: the angle (1 °/h over 1 s is 1 arcsec) is accumulated and sent in whole
// quanta, the remainder carried to the next sample. A quantum of 0 passes the rate through.
class PulseOutput {
 public:
  PulseOutput(double quantum_arcsec, double dt_s) : quantum_(quantum_arcsec), dt_(dt_s) {}

  double operator()(double rate_dph) {
    if (quantum_ <= 0.0) return rate_dph;
    untransmitted_ += rate_dph * dt_;
    const double pulses = std::round(untransmitted_ / quantum_);
    untransmitted_ -= pulses * quantum_;
    return pulses * quantum_ / dt_;
  }

 private:
  double quantum_;
  double dt_;
  double untransmitted_ = 0.0;  // arcsec
};

// A reading rounded to the instrument's resolution (0: no rounding).
inline double at_resolution(double reading, double resolution) {
  return resolution > 0.0 ? std::round(reading / resolution) * resolution : reading;
}

}  // namespace thermodrift::sim
