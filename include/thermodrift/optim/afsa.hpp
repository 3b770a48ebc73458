// The Artificial Fish Swarm Algorithm (Li Xiaolei, 2002) as the paper uses it to
// pick (C, σ), plus the common adaptive variant whose visual range and step shrink over
// the run. docs/optim.md states the algorithm as implemented.
#pragma once

#include <string>

#include "thermodrift/optim/box.hpp"
#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift::optim {

class Afsa {
 public:
  // How visual range and step go from their initial values (iteration 0) to their
  // floors (last iteration).
  enum class Schedule {
    constant,     // the paper's AFSA: r and λ fixed, the floors are unused
    linear,       // r_t = r + (r_floor - r) t/(T-1)
    exponential,  // r_t = r (r_floor / r)^(t/(T-1)): halves at a steady rate, fine steps late
  };

  // Distances are Euclidean in the unit cube of the box (log dimensions in log10), so
  // visual_range = 0.1 is a tenth of every side whatever the units.
  struct Options {
    int fish = 20;                          // n, swarm size
    int iterations = 60;                    // T, iterations after the initial scatter
    double visual_range = 0.5;              // r: neighbours and prey probes lie within it
    double step = 0.3;                      // λ: longest move of one behaviour
    double crowding_factor = 0.5;           // δ in (0, 1): crowded when n_i / n >= δ
    int try_limit = 4;                      // m: prey probes before a random move
    Schedule schedule = Schedule::exponential;  // shrink r and λ so the end of the run refines
    double visual_range_floor = 0.002;      // r at the last iteration (linear, exponential)
    double step_floor = 0.001;              // λ at the last iteration (linear, exponential)
    int stall_iterations = 0;               // stop (converged) after this many iterations in which
                                            //   the bulletin board improved by <= stall_tolerance; 0: never
    double stall_tolerance = 0.0;           // absolute improvement that counts as progress

    bool IsValid(std::string* why) const;
  };

  Afsa() = default;
  explicit Afsa(Options options);  // throws UsageError when !options.IsValid

  const Options& options() const { return options_; }

  // Minimises `objective` over `box`. The result is the bulletin board: the best point of
  // every point evaluated (fish, swarm centres, prey probes). Identical for any
  // control.threads. Throws UsageError for an invalid box or control.
  OptimizationResult optimize(const Objective& objective, const Box& box,
                              const RunControl& control = {}) const;

  // Visual range and step in iteration t (0-based) of the schedule.
  double visual_range_at(int iteration) const;
  double step_at(int iteration) const;

 private:
  Options options_;
};

}  // namespace thermodrift::optim
