// AFSA as implemented (minimisation; "food" is -f, so "better" means lower f):
//
// Each iteration t works on the swarm frozen at its start (positions X, values Y) and
// visual range r_t, step λ_t. For fish i, with its own random stream (seed, t, i):
//   neighbours N_i = { j != i : ||X_j - X_i|| < r_t },  n_i = |N_i|,
//   crowded  <=> n_i / n >= δ.
//   swarm:  centre X_c = mean of N_i; if n_i > 0, not crowded and f(X_c) < Y_i,
//           candidate X_i + γ λ_t (X_c - X_i)/||X_c - X_i||, else prey.
//   follow: X_b = neighbour with the lowest Y; if n_i > 0, not crowded and Y_b < Y_i,
//           candidate towards X_b the same way, else prey.
//   prey:   up to m probes X_p = X_i + (uniform point of the ball of radius r_t); the
//           first with f(X_p) < Y_i gives the candidate towards X_p; if none, the
//           candidate is a random move X_i + (uniform point of the ball of radius λ_t).
// γ ~ U(0, 1), and a move never passes its target (length min(γ λ_t, distance)).
// The fish moves to its best candidate (Li's original: swarm and follow are both tried and
// the better kept), even when that is worse than where it was: that is how it escapes.
// When swarm and follow both fall back to prey, one prey serves both: two preys from the
// same state are draws of one distribution, and sharing halves the cost.
// Everything is clamped to the unit cube. The bulletin board (best point ever evaluated)
// lives in the BatchEvaluator and is the result.
//
// Batches per iteration: the swarm centres; then prey probe k of every fish still
// preying (k = 1..m); then every fish's candidates. Each fish's choices depend only on the
// frozen swarm, its own stream and values of its own points, so the thread count cannot
// change them.
#include "thermodrift/optim/afsa.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/error.hpp"
#include "thermodrift/optim/batch_evaluator.hpp"
#include "thermodrift/optim/random_stream.hpp"

namespace thermodrift::optim {

namespace {

Eigen::VectorXd ClampToCube(Eigen::VectorXd point) { return point.cwiseMax(0.0).cwiseMin(1.0); }

// X + γ λ (target - X)/||target - X||, but not past the target.
Eigen::VectorXd MoveToward(const Eigen::VectorXd& from, const Eigen::VectorXd& target, double step,
                           RandomStream& random) {
  const Eigen::VectorXd direction = target - from;
  const double distance = direction.norm();
  const double length = random.uniform() * step;
  if (distance == 0.0) return from;
  if (length >= distance) return target;
  return ClampToCube(from + direction * (length / distance));
}

Eigen::VectorXd RandomMove(const Eigen::VectorXd& from, double radius, RandomStream& random) {
  return ClampToCube(from + random.ball_offset(from.size(), radius));
}

struct Swarm {
  std::vector<Eigen::VectorXd> positions;  // unit cube
  std::vector<double> values;              // f at positions
};

// One fish's work within an iteration.
struct FishPlan {
  explicit FishPlan(RandomStream stream) : random(stream) {}
  RandomStream random;
  bool swarm_possible = false;      // has neighbours and is not crowded
  Eigen::VectorXd centre;
  bool follow_succeeds = false;
  Eigen::VectorXd best_neighbour;
  bool preying = false;             // swarm or follow fell back to prey, no better probe yet
  std::vector<Eigen::VectorXd> candidates;
};

FishPlan Perceive(const Swarm& swarm, std::size_t fish, double visual_range, double crowding_factor,
                  RandomStream stream) {
  FishPlan plan(stream);
  const Eigen::VectorXd& here = swarm.positions[fish];
  const Eigen::Index dim = here.size();
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(dim);
  long neighbours = 0;
  std::size_t best = fish;
  for (std::size_t j = 0; j < swarm.positions.size(); ++j) {
    if (j == fish || (swarm.positions[j] - here).norm() >= visual_range) continue;
    ++neighbours;
    sum += swarm.positions[j];
    if (best == fish || swarm.values[j] < swarm.values[best]) best = j;
  }
  const bool crowded = static_cast<double>(neighbours) / static_cast<double>(swarm.positions.size()) >=
                       crowding_factor;
  plan.swarm_possible = neighbours > 0 && !crowded;
  if (plan.swarm_possible) {
    plan.centre = sum / static_cast<double>(neighbours);
    plan.best_neighbour = swarm.positions[best];
    plan.follow_succeeds = swarm.values[best] < swarm.values[fish];
  }
  return plan;
}

// One iteration; false when the evaluator says stop (the swarm is then left as it was).
bool Swim(Swarm& swarm, const Afsa::Options& options, int iteration, std::uint64_t seed,
          double visual_range, double step, BatchEvaluator& evaluator) {
  const std::size_t fish_count = swarm.positions.size();
  std::vector<FishPlan> plans;
  plans.reserve(fish_count);
  for (std::size_t i = 0; i < fish_count; ++i)
    plans.push_back(Perceive(swarm, i, visual_range, options.crowding_factor,
                             RandomStream(seed, static_cast<std::uint64_t>(iteration) + 1, i)));

  // Swarm centres.
  std::vector<Eigen::VectorXd> batch;
  std::vector<std::size_t> owner;
  for (std::size_t i = 0; i < fish_count; ++i)
    if (plans[i].swarm_possible) {
      batch.push_back(plans[i].centre);
      owner.push_back(i);
    }
  std::vector<bool> swarm_succeeds(fish_count, false);
  if (!batch.empty()) {
    const auto centre_values = evaluator.evaluate(batch);
    if (evaluator.should_stop()) return false;
    for (std::size_t k = 0; k < owner.size(); ++k)
      swarm_succeeds[owner[k]] = centre_values[k] < swarm.values[owner[k]];
  }
  for (std::size_t i = 0; i < fish_count; ++i) {
    FishPlan& plan = plans[i];
    const Eigen::VectorXd& here = swarm.positions[i];
    if (swarm_succeeds[i]) plan.candidates.push_back(MoveToward(here, plan.centre, step, plan.random));
    if (plan.follow_succeeds)
      plan.candidates.push_back(MoveToward(here, plan.best_neighbour, step, plan.random));
    plan.preying = !swarm_succeeds[i] || !plan.follow_succeeds;
  }

  // Prey: probe k of every fish still preying, as one batch.
  for (int probe = 0; probe < options.try_limit; ++probe) {
    batch.clear();
    owner.clear();
    for (std::size_t i = 0; i < fish_count; ++i)
      if (plans[i].preying) {
        batch.push_back(RandomMove(swarm.positions[i], visual_range, plans[i].random));
        owner.push_back(i);
      }
    if (batch.empty()) break;
    const auto probe_values = evaluator.evaluate(batch);
    if (evaluator.should_stop()) return false;
    for (std::size_t k = 0; k < owner.size(); ++k) {
      FishPlan& plan = plans[owner[k]];
      if (probe_values[k] < swarm.values[owner[k]]) {
        plan.candidates.push_back(MoveToward(swarm.positions[owner[k]], batch[k], step, plan.random));
        plan.preying = false;
      }
    }
  }
  for (std::size_t i = 0; i < fish_count; ++i)
    if (plans[i].preying)
      plans[i].candidates.push_back(RandomMove(swarm.positions[i], step, plans[i].random));

  // Candidates: each fish moves to its best one.
  batch.clear();
  owner.clear();
  for (std::size_t i = 0; i < fish_count; ++i)
    for (auto& candidate : plans[i].candidates) {
      batch.push_back(std::move(candidate));
      owner.push_back(i);
    }
  const auto candidate_values = evaluator.evaluate(batch);
  if (evaluator.should_stop()) return false;
  std::vector<bool> moved(fish_count, false);
  for (std::size_t k = 0; k < owner.size(); ++k) {
    const std::size_t i = owner[k];
    if (!moved[i] || candidate_values[k] < swarm.values[i]) {
      swarm.positions[i] = batch[k];
      swarm.values[i] = candidate_values[k];
      moved[i] = true;
    }
  }
  return true;
}

double Scheduled(Afsa::Schedule schedule, double initial, double floor, int iteration, int iterations) {
  if (schedule == Afsa::Schedule::constant || iterations <= 1) return initial;
  const double progress = static_cast<double>(iteration) / static_cast<double>(iterations - 1);
  if (schedule == Afsa::Schedule::linear) return initial + (floor - initial) * progress;
  return initial * std::pow(floor / initial, progress);
}

}  // namespace

bool Afsa::Options::IsValid(std::string* why) const {
  const Invalid fail(why, "afsa");
  if (fish < 1) return fail(fmt::format("fish must be >= 1, got {}", fish));
  if (iterations < 0) return fail(fmt::format("iterations must be >= 0, got {}", iterations));
  if (!(visual_range > 0.0) || !std::isfinite(visual_range))
    return fail(fmt::format("visual_range must be > 0, got {}", visual_range));
  if (!(step > 0.0) || !std::isfinite(step)) return fail(fmt::format("step must be > 0, got {}", step));
  if (!(crowding_factor > 0.0 && crowding_factor < 1.0))
    return fail(fmt::format("crowding_factor must be in (0, 1), got {}", crowding_factor));
  if (try_limit < 1) return fail(fmt::format("try_limit must be >= 1, got {}", try_limit));
  if (schedule != Schedule::constant) {
    if (!(visual_range_floor > 0.0 && visual_range_floor <= visual_range))
      return fail(fmt::format("visual_range_floor must be in (0, visual_range], got {}",
                              visual_range_floor));
    if (!(step_floor > 0.0 && step_floor <= step))
      return fail(fmt::format("step_floor must be in (0, step], got {}", step_floor));
  }
  if (stall_iterations < 0)
    return fail(fmt::format("stall_iterations must be >= 0, got {}", stall_iterations));
  if (!(stall_tolerance >= 0.0))
    return fail(fmt::format("stall_tolerance must be >= 0, got {}", stall_tolerance));
  return true;
}

Afsa::Afsa(Options options) : options_(std::move(options)) {
  std::string why;
  if (!options_.IsValid(&why)) throw UsageError(why);
}

double Afsa::visual_range_at(int iteration) const {
  return Scheduled(options_.schedule, options_.visual_range, options_.visual_range_floor, iteration,
                   options_.iterations);
}

double Afsa::step_at(int iteration) const {
  return Scheduled(options_.schedule, options_.step, options_.step_floor, iteration, options_.iterations);
}

OptimizationResult Afsa::optimize(const Objective& objective, const Box& box,
                                  const RunControl& control) const {
  BatchEvaluator evaluator(objective, box, control);
  const auto total = static_cast<double>(options_.iterations + 1);

  // Scatter the fish uniformly over the box (stream 0 of the seed).
  Swarm swarm;
  for (int i = 0; i < options_.fish; ++i) {
    RandomStream random(control.seed, 0, static_cast<std::uint64_t>(i));
    swarm.positions.push_back(random.unit_cube_point(box.dimension()));
  }
  evaluator.set_iteration(0, 0.0);
  swarm.values = evaluator.evaluate(swarm.positions);
  if (evaluator.should_stop()) return evaluator.Result(Termination::budget_exhausted, 0);

  int completed = 0;
  int stalled = 0;
  double board_before = evaluator.best_value();
  for (int t = 0; t < options_.iterations; ++t) {
    evaluator.set_iteration(t + 1, (t + 1) / total);
    if (!Swim(swarm, options_, t, control.seed, visual_range_at(t), step_at(t), evaluator)) break;
    completed = t + 1;
    if (options_.stall_iterations > 0) {
      // (board_before - best) is NaN only when both are +inf: nothing finite seen yet.
      const bool improved = board_before - evaluator.best_value() > options_.stall_tolerance;
      stalled = improved ? 0 : stalled + 1;
      board_before = evaluator.best_value();
      if (stalled >= options_.stall_iterations)
        return evaluator.Result(Termination::converged, completed);
    }
  }
  return evaluator.Result(Termination::budget_exhausted, completed);
}

}  // namespace thermodrift::optim
