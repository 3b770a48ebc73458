// Simulates a 3-axis FOG unit in a temperature chamber with known true drift.
// The model and its defaults are in docs/simulator.md.
#pragma once

#include "thermodrift/sim/chamber_profile.hpp"
#include "thermodrift/sim/chamber_run.hpp"
#include "thermodrift/sim/options.hpp"
#include "thermodrift/sim/standard_normal.hpp"

namespace thermodrift::sim {

// Runs the whole test. Deterministic given the options: the true drift depends only on
// the physical options, the noise also on options.seed. Throws UsageError when the
// options are not valid.
// Asks `stop` every 4096 rows (Interrupted("simulation stopped")).
ChamberRun simulate(const SimulatorOptions& options, const StopToken& stop = {});

}  // namespace thermodrift::sim
