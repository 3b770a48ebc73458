// An estimate, from a log alone (no true drift known), of the noise floor: the variance
// of the gyro noise left after the pipeline's trailing moving average. No drift model
// fitted to data smoothed that way can have a residual MSE much below it.
//
// For white noise of variance σ² the mean of w samples has variance σ²/w, which is also
// the Allan variance at τ = window. The Allan variance differences consecutive window
// means, so a drift trend (a 1 °C/min ramp) swamps it; this estimate uses the Hadamard
// (second) difference of overlapping window means instead,
//
//   d_k = m(t_k) - 2·m(t_k - τ) + m(t_k - 2τ),   E[d²] = 6·σ²/w for white noise,
//
// which cancels a linear drift, and takes the median of d² over the log divided by
// 6 · 0.4549 (the median of χ²₁), so the few windows at the corners of a temperature
// profile, where the drift bends, do not count. What it does not count: noise correlated
// over longer than the window (bias instability, a Gauss-Markov bias with a correlation
// time of minutes) is mostly cancelled by the differences, so the estimate is low by
// about the part of the floor such noise makes: on the simulator's default run at a 100 s
// window it lands 5-24 % below the true floor (five seeds, three axes; docs/design.md).
// A quantized gyro output makes d² discrete, so the median moves in steps of a few per
// cent. With windows long enough for the drift's curvature to dominate (≳ 300 s on a
// 1 °C/min profile) it is high, by 2-4 times there.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift {

struct NoiseFloorEstimate {
  double variance = 0;            // (°/h)², of the smoothed noise: an estimate
  std::size_t differences = 0;    // second differences the median was taken over
  bool usable() const { return differences > 0; }
};

// `time` (s, increasing) and `gyro` (°/h) of one axis; `window_s` the moving-average
// window (> 0). A step longer than the window restarts the windows (a gap). A log shorter
// than three windows gives differences = 0. UsageError on a window <= 0 or sizes that differ.
NoiseFloorEstimate estimate_noise_floor(std::span<const double> time, std::span<const double> gyro,
                                        double window_s);

// The same over several logs of one axis, pooled: the median of every log's squared
// differences together.
NoiseFloorEstimate estimate_noise_floor(const std::vector<ChamberLog>& logs, std::size_t axis, double window_s);

}  // namespace thermodrift
