// Burst logs: short bursts of fast samples with long gaps between them (5 s at 50 Hz
// every 5 min, say), as loggers record long thermal tests to save memory. Each burst is
// too short for the 100 s smoothing and the rate span to settle in, so read as it is the
// log would never be ready. Instead each burst's mean becomes one sample, and the
// pipeline's smoothing and rates work on the burst means (docs/data.md, "Burst logs").
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift {

// When `log` is a burst log whose bursts are shorter than `warm_up_seconds` (the
// pipeline's smoothing + rate span), what its bursts are; nullopt otherwise. A burst is a
// run of rows whose steps are at most max(10 x the median step, 1 s); a burst log has at
// least 3 bursts, most of them shorter than the warm-up, and gaps longer than the bursts.
std::optional<BurstSummary> find_bursts(const ChamberLog& log, double warm_up_seconds);

// The log with each burst replaced by one row: the mean time, gyro and temperature of
// its rows, the file line of its first row; `bursts` records what was collapsed.
ChamberLog collapse_bursts(const ChamberLog& log, const BurstSummary& bursts);

// The bursts of `log` collapsed when it is a burst log (find_bursts), else `log` as it is.
ChamberLog collapse_if_bursts(ChamberLog log, double warm_up_seconds);

// The log with its rows averaged in bins of `seconds` from its first row's time: one row
// per bin that holds any, its mean time, gyro and temperature and its first row's line.
// A gap stays a gap. The feature search reads a fast log this way (tune/calibration.cpp).
ChamberLog binned(const ChamberLog& log, double seconds);

}  // namespace thermodrift
