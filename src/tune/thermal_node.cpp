#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>

#include "thermodrift/error.hpp"
#include "thermodrift/tune/feature_selection.hpp"
#include "tune/term_columns.hpp"

namespace thermodrift {

namespace {

// The memory rate scales of the searches whose fits are averaged (°C/min; 0: the default,
// kDirectionRateScale = 0.2): about a factor 3 either side of it.
constexpr double kMemoryRateScales[] = {0, 0.07, 0.5};

// The node's level and rate as terms: what the dynamic terms that read them are built on.
struct NodeNames {
  std::string level, rate;
  double tau = 0;        // the node's whole lag (T1 + T2): what lag-reading terms take as their lag
  double first_tau = 0;  // T1: the lag whose rate gives the direction of travel
};

// A term linear in the node's dynamics, added to the node's static map when it pays.
struct DynamicTerm {
  enum class Kind {
    gradient_rate, memory, second_lag, play, channel_gradient, channel_gradient_rate,
    asymmetric_rate,  // the node's rate times the sign of its travel: heating and cooling rates weigh differently
    rate_tempco,      // the node's rate times its level: a rate sensitivity that changes with temperature
    turn_on,          // exp(-t/τ) since power-on: the gyro's turn-on transient
    self_heating      // exp(-t/τ), τ the node's lag: heat switched on upstream of the node settling through it
  } kind;
  double tau = 0;  // TG of gradrate:τ:TG, TD of dir:TD:τ, the second lag's own τ; W (°C) of play:τ:W; τ of on:τ
  double rate_scale = 0;  // R0 of a memory, °C/min (0: the default, kDirectionRateScale); not refined
  std::string channel_term{};  // grad:A-B or gradrate:A-B: a measured gradient, no constant of its own

  bool measured() const { return kind == Kind::channel_gradient || kind == Kind::channel_gradient_rate; }
  // Terms without a constant of their own to refine.
  bool fixed() const {
    return measured() || kind == Kind::asymmetric_rate || kind == Kind::rate_tempco || kind == Kind::self_heating;
  }
  // Terms that describe the start of a run rather than the node's dynamics.
  bool start_transient() const { return kind == Kind::turn_on || kind == Kind::self_heating; }

  std::string name(const NodeNames& node) const {
    switch (kind) {
      case Kind::gradient_rate: return fmt::format("gradrate:{}:{}", node.tau, tau);
      case Kind::memory:
        return rate_scale > 0 ? fmt::format("dir:{}:{}:{}", tau, node.tau, rate_scale) : fmt::format("dir:{}:{}", tau, node.tau);
      case Kind::second_lag: return fmt::format("lag:{}", tau);
      case Kind::play: return fmt::format("play:{}:{}", node.tau, tau);
      case Kind::channel_gradient:
      case Kind::channel_gradient_rate: return channel_term;
      // The sign of travel is a fast memory (60 s) of the node's first lag's rate, saturated
      // beyond 0.05 °C/min: the product is the rate's magnitude, smooth through zero.
      case Kind::asymmetric_rate: return fmt::format("{}*dir:60:{}:0.05", node.rate, node.first_tau);
      case Kind::rate_tempco: return fmt::format("{}*{}", node.level, node.rate);
      case Kind::turn_on: return fmt::format("on:{}", tau);
      case Kind::self_heating: return fmt::format("on:{}", node.tau);
    }
    return {};
  }
  // The range of the constant, and the step it is rounded to. Memories and gradient lags
  // beyond these follow the log's own course more than any physics; a play wider than
  // 10 °C is a static map, one narrower than 0.2 °C is noise on the node.
  double shortest(double min_time_constant) const { return kind == Kind::play ? 0.2 : min_time_constant / 2; }
  double longest() const {
    switch (kind) {
      case Kind::gradient_rate: return 1920;
      case Kind::memory: return 3000;
      case Kind::second_lag: return 1200;
      case Kind::play: return 10;
      case Kind::turn_on: return 1200;
      case Kind::self_heating:
      case Kind::channel_gradient:
      case Kind::channel_gradient_rate:
      case Kind::asymmetric_rate:
      case Kind::rate_tempco: return 0;
    }
    return 0;
  }
  double resolution() const { return kind == Kind::play ? 0.01 : 1.0; }
  bool operator==(const DynamicTerm&) const = default;
};

// A constant of a model as the refinement moves it: in log scale, rounded to `resolution`
// (whole seconds for time constants) within [low, high].
struct Constant {
  double* value;
  double resolution = 1;
  double low = 0, high = 0;
  // Divided by the steps per unit, not multiplied by the step: 230 · 0.01 is
  // 2.3000000000000003, 230 / 100 is 2.3, the constant the model file then names.
  double rounded(double v) const { return std::round(v / resolution) / (1.0 / resolution); }
  bool inside() const { return *value >= low && *value <= high; }
};

// One thermal node behind the axis' sensor: its temperature N (a lag τ of the smoothed ΔT,
// two lags in series, or a lag with a lead for a sensor on another thermal path) through a
// piecewise-linear static map (N and hinges at fixed knots), its rate, the sensor's own
// rate, and dynamic terms linear in the node's state.
struct NodeModel {
  double tau = 0;   // T1: the node's (first) lag
  double tau2 = 0;  // T2: a second lag in series (0: none), a coil two nodes behind the sensor
  double zero = 0;  // TL: the lead of a node on another thermal path than the sensor's (0: none)
  std::vector<double> knots;  // °C of ΔT
  std::vector<DynamicTerm> dynamics;

  bool plain() const { return tau2 == 0 && zero == 0; }
  // Dynamic terms modelled on the node (a measured gradient is not, nor a start-of-run
  // term, which describes how the run began, not the node): at most max_dynamic_terms.
  std::size_t modelled_dynamics() const {
    return static_cast<std::size_t>(std::count_if(dynamics.begin(), dynamics.end(), [](const DynamicTerm& t) {
      return !t.measured() && !t.start_transient();
    }));
  }
  // The lag the dynamic terms read: the node's, or the sum of a series pair's.
  double dynamics_tau() const { return tau + tau2; }
  // The node's level and rate as terms (a lead-lag node's: its lag's, which the lead shifts
  // by a rate term the model already has).
  NodeNames names() const {
    return {tau2 > 0 ? fmt::format("lag2:{}:{}", tau, tau2) : fmt::format("lag:{}", tau),
            tau2 > 0 ? fmt::format("lag2rate:{}:{}", tau, tau2) : fmt::format("lagrate:{}", tau), dynamics_tau(), tau};
  }

  std::vector<std::string> terms() const {
    const NodeNames node = names();
    std::vector<std::string> out{node.level};
    for (const double knot : knots) {
      out.push_back(plain() ? fmt::format("hinge:{}:{}", tau, knot) : fmt::format("nodehinge:{}:{}:{}:{}", tau, tau2, zero, knot));
    }
    out.push_back(fmt::format("lagrate:{}", tau));
    if (tau2 > 0) out.push_back(node.rate);
    out.push_back("rate");
    for (const auto& term : dynamics) out.push_back(term.name(node));
    return out;
  }

  // The constants a refinement moves: the node's, then each dynamic term's. `longest` bounds
  // the time constants, `shortest` the node's.
  std::vector<Constant> constants(double shortest, double longest) {
    std::vector<Constant> out = {{&tau, 1, shortest, longest}};
    if (tau2 > 0) out.push_back({&tau2, 1, shortest, longest});
    if (zero > 0) out.push_back({&zero, 1, shortest, longest});
    for (auto& term : dynamics) {
      if (term.fixed()) continue;
      out.push_back({&term.tau, term.resolution(), term.shortest(2 * shortest),
                     term.kind == DynamicTerm::Kind::play ? term.longest() : std::min(term.longest(), longest)});
    }
    return out;
  }
};

// Knots spaced evenly between the 1st and 99th percentiles of the training ΔT, rounded to
// 0.1 °C: evenly, not at quantiles, since a soak piles samples at one temperature and
// knots crowded there would bend the map sharply where nothing constrains it.
std::vector<double> spread_knots(const Eigen::VectorXd& delta_t, std::size_t count) {
  std::vector<double> sorted(delta_t.data(), delta_t.data() + delta_t.size());
  std::sort(sorted.begin(), sorted.end());
  if (sorted.empty() || count == 0) return {};
  const auto at = [&](double p) { return sorted[static_cast<std::size_t>(p * static_cast<double>(sorted.size() - 1))]; };
  const double low = at(0.01), high = at(0.99);
  std::vector<double> knots;
  for (std::size_t j = 1; j <= count; ++j) {
    const double knot = std::round((low + (high - low) * static_cast<double>(j) / static_cast<double>(count + 1)) * 10.0) / 10.0;
    if (knots.empty() || knot > knots.back() + 0.05) knots.push_back(knot);
  }
  return knots;
}

// A second lag this close to the node's is nearly the same column twice: their difference
// fits noise with large opposite coefficients. Two terms of one kind do the same, so a
// model has at most one of each: one Shupe term, one memory, one second node.
constexpr double kDistinctRatio = 1.5;

bool distinct(const NodeModel& model) {
  for (std::size_t i = 0; i < model.dynamics.size(); ++i) {
    const auto& a = model.dynamics[i];
    if (!a.fixed() && a.tau > a.longest()) return false;
    if (a.kind == DynamicTerm::Kind::second_lag &&
        std::max(a.tau, model.dynamics_tau()) < kDistinctRatio * std::min(a.tau, model.dynamics_tau())) {
      return false;
    }
    for (std::size_t j = i + 1; j < model.dynamics.size(); ++j) {
      const auto& b = model.dynamics[j];
      if (a.kind != b.kind) continue;
      // One Shupe term, one memory, one second node; plays twice when their widths are at
      // least twice apart (a Preisach sum: hysteresis of several widths).
      if (a.kind != DynamicTerm::Kind::play || std::max(a.tau, b.tau) < 2 * std::min(a.tau, b.tau)) return false;
    }
  }
  return true;
}

double training_span_seconds(const std::vector<ChamberLog>& logs) {
  double span = 0;
  for (const auto& log : logs) {
    if (log.rows() > 1) span += log.time.back() - log.time.front();
  }
  return span;
}

}  // namespace

FeatureSelection identify_thermal_node(const std::vector<ChamberLog>& logs, std::size_t axis,
                                       const Pipeline& pipeline, const FeatureSelectionOptions& options) {
  // One column cache per temperature channel the node may be found on: the axis' own, and
  // with one thermometer per axis (or more) every other one too. Another axis' thermometer
  // can sit on this axis' coil (or nearer to it than its own, which may be on another
  // block): a node on that channel needs no lead to undo its own sensor's lag.
  const std::size_t own = temperature_channel_per_axis(logs.front()).at(axis);
  std::vector<std::size_t> channels{own};
  if (options.other_channels && logs.front().temperature.size() >= logs.front().axes()) {
    for (std::size_t c = 0; c < logs.front().temperature.size(); ++c) {
      if (c != own) channels.push_back(c);
    }
  }
  std::vector<ColumnCache> caches;
  caches.reserve(channels.size());
  for (const std::size_t channel : channels) {
    Pipeline on_channel = pipeline;
    if (channel != own) on_channel.temperature_channel = channel;
    caches.emplace_back(logs, axis, on_channel, true);
  }
  ColumnCache* cache = &caches.front();
  const Eigen::VectorXd& y = cache->target();
  if (y.size() < 4 * options.folds) {
    throw UsageError(fmt::format("--features auto: {} samples are too few for {}-fold identification", y.size(),
                                 options.folds));
  }
  FeatureSelection result;
  result.scored_by = "least_squares";
  result.held_out = cache->blocks(options.folds, options.folds_by);
  // A set's score: its blocked CV (the geometric mean of the blocks' MSEs, or their pooled
  // MSE: options.cv_score), times (c / max_cancellation)² when its fit cancels c times more.
  const bool typical = options.cv_score == FeatureSelectionOptions::CvScore::geometric;
  auto penalized = [&](const LeastSquaresScore& scored, bool by_typical_block) {
    const double cv = by_typical_block ? scored.typical_block_mse() : scored.cv_mse;
    const double excess = scored.cancellation / options.max_cancellation;
    return excess > 1 ? cv * excess * excess : cv;
  };
  // The node's level and its hinges are one part: a piecewise-linear map cancels by design.
  auto grouped = [](const NodeModel& model) { return static_cast<Eigen::Index>(1 + model.knots.size()); };
  // The search scores sets on the cache's sparse columns ... A set is scored once: the
  // refinement's pattern search steps back over points it has left, its simplex rounds
  // vertices onto the same whole seconds, and the members offer the same terms to one node.
  std::unordered_map<std::string, double> scores;  // by channel and terms
  auto score = [&](const NodeModel& model) {
    options.stop.throw_if_requested("feature identification");
    ++result.candidates_scored;
    const std::vector<std::string> names = model.terms();
    std::string key = std::to_string(cache - caches.data());
    for (const auto& name : names) key += ' ' + name;
    const auto [at, fresh] = scores.try_emplace(std::move(key), 0.0);
    if (fresh) at->second = penalized(cache->cv_score(names, result.held_out.blocks, grouped(model)), typical);
    return at->second;
  };
  result.start_mse = typical ? cache->cv_score({}, result.held_out.blocks, 0).typical_block_mse()
                             : least_squares_cv(Eigen::MatrixXd(y.size(), 0), y, result.held_out.blocks);

  // A lag is identifiable when the log holds several of it: at most a quarter of its span.
  const double longest = std::min(options.max_time_constant, training_span_seconds(logs) / 4.0);
  std::vector<double> grid;
  for (int k = 0;; ++k) {
    const double tau = std::round(options.min_time_constant * std::pow(std::sqrt(2.0), k));
    if (tau > longest) break;
    grid.push_back(tau);
  }
  if (grid.empty()) grid.push_back(options.min_time_constant);

  // A model's constants are all identifiable from the log and its terms distinct.
  const double shortest = options.min_time_constant / 2;
  auto constants = [&](NodeModel& m) { return m.constants(shortest, longest); };
  auto feasible = [&](NodeModel& m) {
    for (const Constant& constant : constants(m)) {
      if (!constant.inside()) return false;
    }
    return m.tau + m.tau2 <= longest && distinct(m);
  };

  // Every node on the grid under `base`'s static map and dynamic terms: the best single lag,
  // and the best node with a second pole or a zero (nodehinge): a coil two nodes behind the
  // sensor, or on another thermal path than the sensor's (the sensor on another axis' block
  // lags the common source by TL, the coil by T1). The series pair takes T2 <= T1 (the
  // order of two lags does not matter). (A node that leads the sensor, ΔT + τ·rate, was
  // tried as an alternative: on the development laws it won the CV by a fifth where the
  // sensor sat on another block and then failed the next cycle by 100-600x; the lead-lag
  // holds that case with a lag to smooth the rate.)
  struct GridNodes {
    NodeModel lag, structured;
    double lag_cv = kInfinity, structured_cv = kInfinity;
  };
  auto search_grid = [&](const NodeModel& base) {
    GridNodes found{base, base};
    for (const double t1 : grid) {
      for (const double other : grid) {
        for (const int shape : {0, 1, 2}) {  // a single lag, two lags in series, a lag with a lead
          NodeModel trial = base;
          trial.tau = t1, trial.tau2 = 0, trial.zero = 0;
          if (shape == 0 && other != grid.front()) continue;
          if (shape == 1 && (other > t1 || t1 + other > longest)) continue;
          if (shape == 2 && other == t1) continue;
          if (shape == 1) trial.tau2 = other;
          if (shape == 2) trial.zero = other;
          if (!feasible(trial)) continue;
          const double cv = score(trial);
          double& best_cv = shape == 0 ? found.lag_cv : found.structured_cv;
          if (cv < best_cv) best_cv = cv, (shape == 0 ? found.lag : found.structured) = std::move(trial);
        }
      }
    }
    return found;
  };
  auto describe = [](const NodeModel& m) {
    if (m.tau2 > 0) return fmt::format("lags {} s and {} s in series", m.tau, m.tau2);
    if (m.zero > 0) return fmt::format("lag {} s, lead {} s", m.tau, m.zero);
    return fmt::format("lag {} s", m.tau);
  };

  // The node on one channel: a lag on the grid, then a node with a second pole or a zero,
  // which must beat the single lag by min_gain.
  struct Node {
    NodeModel best, runner_up;  // runner_up: the structure not chosen (plain or structured), for the average
    double best_cv = kInfinity, runner_up_cv = kInfinity;
    double lag_cv = kInfinity;  // the single lag's
    std::vector<SelectionStep> path;
  };
  auto find_node = [&]() {
    NodeModel base;
    base.knots = spread_knots(cache->matrix({"dT"}).col(0), options.knots);
    GridNodes found = search_grid(base);
    Node node{std::move(found.lag), std::move(found.structured), found.lag_cv, found.structured_cv, found.lag_cv, {}};
    node.path.push_back({"node", fmt::format("lag {} s of {} on the grid", node.best.tau, grid.size()), node.best_cv,
                         node.best.terms()});
    if (node.runner_up_cv < (1.0 - options.min_gain) * node.best_cv) {
      std::swap(node.best, node.runner_up), std::swap(node.best_cv, node.runner_up_cv);
      node.path.push_back({"node", describe(node.best), node.best_cv, node.best.terms()});
    }
    return node;
  };
  // On each channel. Another channel is taken when its single lag beats the own channel's
  // by min_gain (a node that is a plain lag of a thermometer needs no lead, which one cycle
  // identifies poorly: development law 13, z, whose own sensor sits 1,900 s upstream on
  // another block, missed other programmes by 1,300x the floor with a lead-lag on it) and
  // the own channel's whole node (the richer nodes included) does not beat its whole node
  // by min_gain (a case thermometer 2,700 s upstream of a coil beat, as a single lag, the
  // axis' own 170 s from the coil behind a second node, and then missed another programme
  // by 1,600x: law 11, y).
  std::vector<Node> nodes;
  for (ColumnCache& on : caches) {
    cache = &on;
    nodes.push_back(find_node());
    if (caches.size() > 1) {
      result.path.push_back({"channel", fmt::format("temperature channel {}: {} (single lag: score {:.6g})",
                                                    channels[nodes.size() - 1] + 1, nodes.back().path.back().term,
                                                    nodes.back().lag_cv),
                             nodes.back().best_cv, nodes.back().best.terms()});
    }
  }
  std::size_t best_channel = 0;
  const double keep = 1.0 - options.min_gain;
  for (std::size_t k = 1; k < nodes.size(); ++k) {
    if (nodes[k].lag_cv < keep * nodes.front().lag_cv && !(nodes.front().best_cv < keep * nodes[k].best_cv) &&
        (best_channel == 0 || nodes[k].best_cv < nodes[best_channel].best_cv)) {
      best_channel = k;
    }
  }

  // Every time constant between grid points (the node's and each dynamic term's): a
  // coordinate pattern search in log scale while the CV MSE falls, then a Nelder-Mead
  // simplex over all of them at once. Constants that act together (the node's lag and a
  // memory's, a Shupe lag and the node's) leave a narrow valley in the CV MSE that moves
  // one constant at a time cannot follow: on the simulator's default unit, y axis, the
  // coordinate search stopped at lag 679 s, memory 889 s, 2x the held-out error of the
  // valley floor near the true 650 s and 1200 s.
  auto refine = [&](NodeModel& model, double& model_cv) {
    NodeModel before = model;
    for (const double step : {0.25, 0.125, 0.0625}) {
      for (bool pass_improved = true; pass_improved;) {
        pass_improved = false;
        for (std::size_t k = 0; k < constants(model).size(); ++k) {
          for (bool improved = true; improved;) {
            improved = false;
            for (const double factor : {std::pow(2.0, step), std::pow(2.0, -step)}) {
              NodeModel trial = model;
              const Constant constant = constants(trial)[k];
              *constant.value = constant.rounded(*constant.value * factor);
              if (*constant.value == *constants(model)[k].value || !feasible(trial)) continue;
              const double cv = score(trial);
              if (cv < model_cv) {
                model = std::move(trial), model_cv = cv, improved = pass_improved = true;
                break;
              }
            }
          }
        }
      }
    }
    const std::size_t dim = constants(model).size();
    if (dim > 1) {
      auto at = [&](const Eigen::VectorXd& v, NodeModel& m) -> double {
        m = model;
        const auto moved = constants(m);
        for (std::size_t k = 0; k < dim; ++k) {
          *moved[k].value = moved[k].rounded(std::exp(v[static_cast<Eigen::Index>(k)]));
        }
        return feasible(m) ? score(m) : kInfinity;
      };
      std::vector<Eigen::VectorXd> simplex(dim + 1, Eigen::VectorXd(static_cast<Eigen::Index>(dim)));
      std::vector<double> f(dim + 1);
      const auto start = constants(model);
      for (std::size_t k = 0; k < dim; ++k) simplex[0][static_cast<Eigen::Index>(k)] = std::log(*start[k].value);
      NodeModel scratch;
      f[0] = model_cv;
      for (std::size_t i = 1; i <= dim; ++i) {
        simplex[i] = simplex[0];
        simplex[i][static_cast<Eigen::Index>(i - 1)] += 0.25 * std::log(2.0);
        f[i] = at(simplex[i], scratch);
      }
      // Stops when the simplex's values agree to 1e-4 or after 30 sets per vertex.
      for (std::size_t evaluations = 0; evaluations < 30 * (dim + 1);) {
        std::vector<std::size_t> order(dim + 1);
        for (std::size_t i = 0; i <= dim; ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return f[i] < f[j]; });
        const std::size_t lowest = order[0], worst = order[dim], second = order[dim - 1];
        if (f[worst] - f[lowest] <= 1e-4 * f[lowest]) break;
        Eigen::VectorXd centre = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(dim));
        for (std::size_t i = 0; i <= dim; ++i) {
          if (i != worst) centre += simplex[i] / static_cast<double>(dim);
        }
        const Eigen::VectorXd reflected = 2.0 * centre - simplex[worst];
        const double f_reflected = at(reflected, scratch);
        ++evaluations;
        if (f_reflected < f[lowest]) {
          const Eigen::VectorXd expanded = 3.0 * centre - 2.0 * simplex[worst];
          const double f_expanded = at(expanded, scratch);
          ++evaluations;
          if (f_expanded < f_reflected) {
            simplex[worst] = expanded, f[worst] = f_expanded;
          } else {
            simplex[worst] = reflected, f[worst] = f_reflected;
          }
        } else if (f_reflected < f[second]) {
          simplex[worst] = reflected, f[worst] = f_reflected;
        } else {
          const Eigen::VectorXd contracted = 0.5 * (centre + simplex[worst]);
          const double f_contracted = at(contracted, scratch);
          ++evaluations;
          if (f_contracted < f[worst]) {
            simplex[worst] = contracted, f[worst] = f_contracted;
          } else {  // shrink towards the lowest vertex
            for (std::size_t i = 0; i <= dim; ++i) {
              if (i == lowest) continue;
              simplex[i] = 0.5 * (simplex[i] + simplex[lowest]);
              f[i] = at(simplex[i], scratch);
              ++evaluations;
            }
          }
        }
      }
      const auto lowest = static_cast<std::size_t>(std::min_element(f.begin(), f.end()) - f.begin());
      if (f[lowest] < model_cv) {
        at(simplex[lowest], scratch);
        model = std::move(scratch), model_cv = f[lowest];
      }
    }
    std::string moves;
    const auto from = constants(before), to = constants(model);
    for (std::size_t k = 0; k < to.size(); ++k) {
      const double was = k < from.size() ? *from[k].value : 0;
      if (was != *to[k].value) moves += fmt::format("{}{} -> {}", moves.empty() ? "" : ", ", was, *to[k].value);
    }
    if (!moves.empty()) result.path.push_back({"tune", moves, model_cv, model.terms()});
  };
  // Dynamic terms, forward from a node: each must cut the CV MSE by more than min_gain.
  // Memories are offered with the rate scale `memory_scale` (0: the default).
  auto grow = [&](NodeModel best, double best_cv, double memory_scale) -> std::pair<NodeModel, double> {
    std::vector<DynamicTerm> candidates;
    for (const double tau : grid) {
      for (const auto kind : {DynamicTerm::Kind::gradient_rate, DynamicTerm::Kind::second_lag}) {
        const DynamicTerm candidate{kind, tau};
        if (tau <= candidate.longest()) candidates.push_back(candidate);
      }
    }
    for (const double tau : {150.0, 300.0, 600.0, 1200.0, 2400.0}) {
      candidates.push_back({DynamicTerm::Kind::memory, tau, memory_scale});
    }
    for (const double width : {0.5, 1.0, 2.0, 4.0}) candidates.push_back({DynamicTerm::Kind::play, width});
    candidates.push_back({DynamicTerm::Kind::asymmetric_rate});
    candidates.push_back({DynamicTerm::Kind::rate_tempco});
    if (options.power_on_start) {
      for (const double tau : {150.0, 300.0, 600.0, 1200.0}) candidates.push_back({DynamicTerm::Kind::turn_on, tau});
      candidates.push_back({DynamicTerm::Kind::self_heating});
    }
    for (const auto& term : channel_candidate_terms(logs.front(), axis)) {
      const bool rate = term.rfind("gradrate:", 0) == 0;
      candidates.push_back({rate ? DynamicTerm::Kind::channel_gradient_rate : DynamicTerm::Kind::channel_gradient, 0, 0, term});
    }
    for (;;) {
      std::vector<std::pair<double, NodeModel>> ranked;
      auto offer = [&](const std::vector<DynamicTerm>& terms) {
        NodeModel trial = best;
        for (const auto& term : terms) {
          if (std::find(trial.dynamics.begin(), trial.dynamics.end(), term) != trial.dynamics.end()) return;
          trial.dynamics.push_back(term);
        }
        if (trial.modelled_dynamics() > options.max_dynamic_terms || !distinct(trial)) return;
        ranked.emplace_back(score(trial), std::move(trial));
      };
      for (const auto& candidate : candidates) {
        offer({candidate});
      }
      // A Shupe term and a memory (or a play) together: each alone is often beaten by a proxy that
      // then blocks the pair (the greedy search's lesson, docs/features.md).
      for (const double tg : {60.0, 120.0, 240.0, 480.0}) {
        for (const double td : {300.0, 600.0, 1200.0}) {
          offer({{DynamicTerm::Kind::gradient_rate, tg}, {DynamicTerm::Kind::memory, td, memory_scale}});
        }
        for (const double width : {0.5, 1.0, 2.0, 4.0}) {
          offer({{DynamicTerm::Kind::gradient_rate, tg}, {DynamicTerm::Kind::play, width}});
        }
      }
      if (ranked.empty()) break;
      std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      // The best few are refined before one is chosen: a term often pays only once the
      // constants it shares have moved.
      NodeModel chosen;
      double chosen_cv = kInfinity;
      const std::size_t silent = result.path.size();
      for (std::size_t i = 0; i < std::min<std::size_t>(ranked.size(), options.refine_top); ++i) {
        auto& [cv, trial] = ranked[i];
        refine(trial, cv);
        if (cv < chosen_cv) chosen_cv = cv, chosen = trial;
      }
      result.path.resize(silent);  // the trials' moves; the chosen one's are in its "add" step
      const std::size_t added = chosen.dynamics.size() - best.dynamics.size();
      if (!(chosen_cv < std::pow(keep, static_cast<double>(added)) * best_cv)) break;
      std::string names;
      for (std::size_t i = best.dynamics.size(); i < chosen.dynamics.size(); ++i) {
        if (!names.empty()) names += ',';  // (not "," + name: GCC 12 warns -Wrestrict on it)
        names += chosen.dynamics[i].name(chosen.names());
      }
      best = std::move(chosen), best_cv = chosen_cv;
      result.path.push_back({"add", names, best_cv, best.terms()});
    }
    return {std::move(best), best_cv};
  };

  // The node again, under the dynamic terms grown on it. The node is chosen first, with only
  // its static map and rates, so an unmodelled memory or play bends its lag or picks a
  // structure that absorbs them; the terms then grown on it make up for the wrong node.
  // Development law 9, y (a coil two lags, 3,059 s and 199 s, behind its thermometer, and a
  // memory): the node found first was a 960 s lag with a 679 s lead, and the model grown on
  // it stayed at 8x the floor in its own CV. So every node on the grid is scored again with
  // the grown terms in the model; the best is refined and grown from, and the result kept
  // when it beats the model by min_gain. At most twice.
  auto renode = [&](NodeModel model, double model_cv, double memory_scale) -> std::pair<NodeModel, double> {
    for (int round = 0; round < 2 && options.node_under_dynamics; ++round) {
      GridNodes found = search_grid(model);
      const bool structured = found.structured_cv < found.lag_cv;
      NodeModel node = structured ? std::move(found.structured) : std::move(found.lag);
      double node_cv = structured ? found.structured_cv : found.lag_cv;
      if (!(node_cv < model_cv)) break;
      const std::size_t silent = result.path.size();
      refine(node, node_cv);
      auto [grown, grown_cv] = grow(std::move(node), node_cv, memory_scale);
      result.path.resize(silent);
      if (!(grown_cv < keep * model_cv)) break;
      model = std::move(grown), model_cv = grown_cv;
      result.path.push_back({"renode", fmt::format("{}, searched again under the dynamic terms", describe(model)),
                             model_cv, model.terms()});
    }
    return {std::move(model), model_cv};
  };

  // One cycle rarely tells a memory from a play, one memory's rate scale from another's, or
  // a lead-lag node from two lags in series: searches that differ only in that find sets
  // whose CV MSE is close and whose held-out errors are not (on development laws 1-20, each
  // was 5-50x better than another on some axes and as much worse on others). So six
  // searches are run, from the chosen node and from the structure not chosen, each with
  // memories of one rate scale, and the least-squares fits of those the CV cannot tell
  // from the best are averaged. The MSE of an average is at most the average of the
  // members' MSEs, so it is never worse than picking one of them at random, which is what
  // choosing by a CV that cannot tell them apart amounts to.
  struct Member {
    NodeModel model;
    double cv = kInfinity;
    std::vector<std::string> terms;
  };
  auto lowest_cv = [](const std::vector<Member>& members) {
    double lowest = kInfinity;
    for (const auto& member : members) lowest = std::min(lowest, member.cv);
    return lowest;
  };
  // The search on channel k from its node: the node and the structure not chosen refined,
  // then the six members grown on them (each node searched again under its terms).
  auto search_channel = [&](std::size_t k) {
    cache = &caches[k];
    for (SelectionStep step : nodes[k].path) {
      if (k != 0) step.term += fmt::format(", on temperature channel {}", channels[k] + 1);
      result.path.push_back(std::move(step));
    }
    NodeModel best = nodes[k].best, runner_up = nodes[k].runner_up;
    double best_cv = nodes[k].best_cv, runner_up_cv = nodes[k].runner_up_cv;
    refine(best, best_cv);
    if (std::isfinite(runner_up_cv)) {
      result.path.push_back({"node", "the structure not chosen, for the average below", runner_up_cv, runner_up.terms()});
      refine(runner_up, runner_up_cv);
    }
    std::vector<Member> members;
    for (const bool runner : {false, true}) {
      if (runner && !std::isfinite(runner_up_cv)) break;
      for (const double scale : kMemoryRateScales) {
        auto [grown, grown_cv] = grow(runner ? runner_up : best, runner ? runner_up_cv : best_cv, scale);
        auto [model, cv] = renode(std::move(grown), grown_cv, scale);
        std::vector<std::string> terms = model.terms();
        result.path.push_back({"member", fmt::format("{}: {}, memories with a rate scale of {} °C/min", members.size() + 1,
                                                     runner ? "the node structure not chosen" : "the node",
                                                     scale > 0 ? scale : kDirectionRateScale),
                               cv, terms});
        members.push_back({std::move(model), cv, std::move(terms)});
      }
    }
    return members;
  };
  const std::size_t first_step = result.path.size();
  std::vector<Member> members = search_channel(best_channel);
  // The channel again, under the dynamic terms. The rule above compares bare nodes; a node
  // on another thermometer can win there and lose once each channel's terms are grown
  // (development law 9, y: another channel's 1,032 s lag beat the own channel's node, and
  // its grown model stayed 5.5 times the CV MSE of the own channel's, 300x the floor on
  // the next cycle against 8.7x). So the own channel is searched too, and the other kept
  // only when its grown model beats the own's by min_gain. The steps of the search not
  // kept are dropped from the path.
  if (best_channel != 0 && options.node_under_dynamics) {
    const std::size_t own_first_step = result.path.size();
    std::vector<Member> own = search_channel(0);
    const double other_cv = lowest_cv(members), own_cv = lowest_cv(own);
    const bool other = other_cv < keep * own_cv;
    const auto steps = [&](std::size_t k) { return result.path.begin() + static_cast<std::ptrdiff_t>(k); };
    if (other) {
      result.path.erase(steps(own_first_step), result.path.end());
    } else {
      result.path.erase(steps(first_step), steps(own_first_step));
      members = std::move(own);
    }
    result.path.push_back({"channel",
                           fmt::format("temperature channel {} grown to a score of {:.6g}, the axis' own to {:.6g}: {} kept",
                                       channels[best_channel] + 1, other_cv, own_cv, other ? "the other" : "the own"),
                           std::min(other_cv, own_cv),
                           std::min_element(members.begin(), members.end(),
                                            [](const Member& a, const Member& b) { return a.cv < b.cv; })
                               ->terms});
    if (!other) best_channel = 0;
  }
  cache = &caches[best_channel];
  if (best_channel != 0) result.temperature_channel = channels[best_channel];
  // Only the members the CV cannot tell from the best (within min_gain of its CV MSE).
  const double lowest = lowest_cv(members);
  std::vector<Member> kept;
  std::string kept_numbers;
  for (std::size_t m = 0; m < members.size(); ++m) {
    if (members[m].cv * (1.0 - options.min_gain) > lowest) continue;
    kept_numbers += fmt::format("{}{}", kept_numbers.empty() ? "" : ", ", m + 1);
    kept.push_back(std::move(members[m]));
  }
  std::vector<std::string> names;
  std::size_t distinct_members = 0;
  for (std::size_t m = 0; m < kept.size(); ++m) {
    const auto repeats = [&](const Member& earlier) { return earlier.terms == kept[m].terms; };
    if (std::none_of(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(m), repeats)) ++distinct_members;
    for (const auto& name : kept[m].terms) {
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
  }
  result.terms = names;
  // ... and what it found is judged and fitted on the model's own columns.
  if (distinct_members == 1) {
    const LeastSquaresScore scored =
        least_squares_cv_score(cache->exact_matrix(names), y, result.held_out.blocks, grouped(kept.front().model));
    result.cv_mse = penalized(scored, false);  // pooled, as averages are
    return result;
  }
  Eigen::VectorXd held_out = Eigen::VectorXd::Zero(y.size());
  const double weight = 1.0 / static_cast<double>(kept.size());
  const Eigen::MatrixXd columns = cache->exact_matrix(names);
  const auto of = [&](const std::vector<std::string>& set) {
    std::vector<Eigen::Index> at;
    for (const auto& name : set) at.push_back(std::find(names.begin(), names.end(), name) - names.begin());
    return Eigen::MatrixXd(columns(Eigen::all, at));
  };
  for (const auto& member : kept) {
    result.averaged_sets.push_back(member.terms);
    held_out += weight * least_squares_cv_predictions(of(member.terms), y, result.held_out.blocks);
  }
  result.cv_mse = held_out_mse(held_out, y, result.held_out.blocks);
  result.linear_fit = averaged_least_squares(columns, y, names, result.averaged_sets);
  result.path.push_back({"average", fmt::format("members {} ({} distinct sets), their fits averaged", kept_numbers, distinct_members),
                         result.cv_mse, names});
  return result;
}

}  // namespace thermodrift
