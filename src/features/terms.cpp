#include "thermodrift/features/terms.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <optional>
#include <cstdlib>
#include <string_view>
#include <utility>
#include <algorithm>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace {

constexpr std::string_view kKnownTerms =
    "dT, rate, lag:TAU, lagrate:TAU, gradrate:TAU:TG, dir:TAU[:LAG[:R0]], grad:A-B, gradrate:A-B, "
    "hinge:TAU:K, lead:TAU, leadhinge:TAU:K, lag2:T1:T2, lag2rate:T1:T2, nodehinge:T1:T2:TL:K, play:TAU:W, "
    "on:TAU, products A*B and powers A^2";
constexpr double kMaxTimeConstant = 1e6;  // s; eleven days is no thermal lag of a gyro
constexpr double kMaxKnot = 1000;  // °C of ΔT: beyond any chamber
constexpr int kMaxPower = 4;
constexpr double kMinRateScale = 0.001, kMaxRateScale = 100;  // °C/min: R0 of dir

[[noreturn]] void bad_term(const std::string& text, const std::string& why) {
  throw UsageError(fmt::format("feature term '{}': {} (known: {})", text, why, kKnownTerms));
}

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return parts;
    start = end + 1;
  }
}

// The whole of `text` as a finite number, or nothing.
std::optional<double> finite_number(std::string_view text) {
  const std::string token(text);
  char* end = nullptr;
  errno = 0;
  const double value = token.empty() ? 0 : std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

double parse_time_constant(const std::string& term, std::string_view text) {
  const std::string token(text);
  const auto value = finite_number(text).value_or(0);
  if (!(value > 0) || value > kMaxTimeConstant) {
    bad_term(term, fmt::format("time constant '{}' must be a number of seconds in (0, {:g}]", token, kMaxTimeConstant));
  }
  return value;
}

// T2 or TL of nodehinge: 0 (none) or a time constant.
double parse_optional_time_constant(const std::string& term, std::string_view text) {
  if (finite_number(text) == 0.0) return 0;
  return parse_time_constant(term, text);
}

// A knot of hinge: a finite temperature difference, °C (negative below the reference).
double parse_level(const std::string& term, std::string_view text) {
  const std::string token(text);
  const auto value = finite_number(text);
  if (!value || std::abs(*value) > kMaxKnot) {
    bad_term(term, fmt::format("knot '{}' must be a temperature difference in [-{:g}, {:g}] °C", token, kMaxKnot, kMaxKnot));
  }
  return *value;
}

// "A-B": two different 1-based channel numbers, returned 0-based.
std::pair<std::size_t, std::size_t> parse_channels(const std::string& term, std::string_view text) {
  const auto parts = split(text, '-');
  std::size_t channels[2] = {0, 0};
  bool valid = parts.size() == 2;
  for (std::size_t i = 0; valid && i < 2; ++i) {
    const std::string_view digits = parts[i];
    valid = !digits.empty() && digits.size() <= 2 && digits.find_first_not_of("0123456789") == std::string_view::npos;
    if (valid) channels[i] = std::stoul(std::string(digits));
    valid = valid && channels[i] >= 1 && channels[i] <= kMaxTemperatureChannels;
  }
  if (!valid || channels[0] == channels[1]) {
    bad_term(term, fmt::format("'{}' must be two different temperature channel numbers A-B, 1..{}", text,
                               kMaxTemperatureChannels));
  }
  return {channels[0] - 1, channels[1] - 1};
}

FeatureAtom parse_atom(const std::string& term, std::string_view text) {
  using Kind = FeatureAtom::Kind;
  if (text == "dT") return {Kind::delta_t};
  if (text == "rate") return {Kind::rate};
  if (text.size() > 1 && text[0] == 'x' && text.find_first_not_of("0123456789", 1) == std::string_view::npos &&
      text.size() <= 7) {
    const auto column = std::stoul(std::string(text.substr(1)));
    if (column >= 1) return {Kind::input, 0, 0, column - 1};
  }
  const auto parts = split(text, ':');
  const std::string_view head = parts.front();
  if (head == "lag" || head == "lagrate") {
    if (parts.size() != 2) bad_term(term, fmt::format("{} takes one time constant: {}:TAU", head, head));
    return {head == "lag" ? Kind::lag : Kind::lag_rate, parse_time_constant(term, parts[1])};
  }
  if ((head == "grad" || head == "gradrate") && parts.size() == 2 && parts[1].find('-') != std::string_view::npos) {
    const auto [a, b] = parse_channels(term, parts[1]);
    FeatureAtom atom{head == "grad" ? Kind::channel_gradient : Kind::channel_gradient_rate};
    atom.channel = a;
    atom.channel2 = b;
    return atom;
  }
  if (head == "grad") bad_term(term, "grad takes two temperature channels: grad:A-B");
  if (head == "gradrate") {
    if (parts.size() != 3) bad_term(term, "gradrate takes two time constants, gradrate:TAU:TG, or two channels, gradrate:A-B");
    return {Kind::gradient_rate, parse_time_constant(term, parts[1]), parse_time_constant(term, parts[2])};
  }
  if (head == "hinge" || head == "leadhinge") {
    if (parts.size() != 3) bad_term(term, fmt::format("{} takes a time constant and a knot: {}:TAU:K", head, head));
    FeatureAtom atom{head == "hinge" ? Kind::hinge : Kind::lead_hinge, parse_time_constant(term, parts[1])};
    atom.level = parse_level(term, parts[2]);
    return atom;
  }
  if (head == "lag2" || head == "lag2rate") {
    if (parts.size() != 3) bad_term(term, fmt::format("{} takes two time constants: {}:T1:T2", head, head));
    return {head == "lag2" ? Kind::lag2 : Kind::lag2_rate, parse_time_constant(term, parts[1]),
            parse_time_constant(term, parts[2])};
  }
  if (head == "nodehinge") {
    if (parts.size() != 5) bad_term(term, "nodehinge takes three time constants and a knot: nodehinge:T1:T2:TL:K");
    FeatureAtom atom{Kind::node_hinge, parse_time_constant(term, parts[1]), parse_optional_time_constant(term, parts[2])};
    atom.zero = parse_optional_time_constant(term, parts[3]);
    atom.level = parse_level(term, parts[4]);
    return atom;
  }
  if (head == "play") {
    if (parts.size() != 3) bad_term(term, "play takes a time constant and a half-width: play:TAU:W");
    FeatureAtom atom{Kind::play, parse_time_constant(term, parts[1])};
    const auto width = finite_number(parts[2]);
    if (!width || !(*width > 0) || *width > kMaxKnot) {
      bad_term(term, fmt::format("half-width '{}' must be a temperature difference in (0, {:g}] °C", parts[2], kMaxKnot));
    }
    atom.level = *width;
    return atom;
  }
  if (head == "on") {
    if (parts.size() != 2) bad_term(term, "on takes one time constant: on:TAU");
    return {Kind::turn_on, parse_time_constant(term, parts[1])};
  }
  if (head == "lead") {
    if (parts.size() != 2) bad_term(term, "lead takes one time constant: lead:TAU");
    return {Kind::lead, parse_time_constant(term, parts[1])};
  }
  if (head == "dir") {
    if (parts.size() < 2 || parts.size() > 4) {
      bad_term(term, "dir takes a time constant, the lag of its rate and a rate scale: dir:TAU[:LAG[:R0]]");
    }
    FeatureAtom atom{Kind::direction, parse_time_constant(term, parts[1])};
    if (parts.size() == 2) return atom;
    atom.tau2 = parts.size() == 4 ? parse_optional_time_constant(term, parts[2]) : parse_time_constant(term, parts[2]);
    if (parts.size() == 4) {
      const auto scale = finite_number(parts[3]);
      if (!scale || !(*scale >= kMinRateScale && *scale <= kMaxRateScale)) {
        bad_term(term, fmt::format("rate scale '{}' must be a rate in [{:g}, {:g}] °C/min", parts[3], kMinRateScale,
                                   kMaxRateScale));
      }
      atom.rate_scale = *scale;
    }
    return atom;
  }
  bad_term(term, fmt::format("unknown atom '{}'", text));
}

double tanh_by_exp(double x) {
  // tanh through exp alone, as the exported C header computes it (no libm beyond exp).
  return 1.0 - 2.0 / (std::exp(2.0 * x) + 1.0);
}

}  // namespace

std::string FeatureAtom::name() const {
  switch (kind) {
    case Kind::delta_t: return "dT";
    case Kind::rate: return "rate";
    case Kind::lag: return fmt::format("lag:{}", tau);
    case Kind::lag_rate: return fmt::format("lagrate:{}", tau);
    case Kind::gradient_rate: return fmt::format("gradrate:{}:{}", tau, tau2);
    case Kind::direction:
      if (rate_scale > 0) return fmt::format("dir:{}:{}:{}", tau, tau2, rate_scale);
      return tau2 > 0 ? fmt::format("dir:{}:{}", tau, tau2) : fmt::format("dir:{}", tau);
    case Kind::input: return fmt::format("x{}", input_index + 1);
    case Kind::channel_gradient: return fmt::format("grad:{}-{}", channel + 1, channel2 + 1);
    case Kind::channel_gradient_rate: return fmt::format("gradrate:{}-{}", channel + 1, channel2 + 1);
    case Kind::hinge: return fmt::format("hinge:{}:{}", tau, level);
    case Kind::lead: return fmt::format("lead:{}", tau);
    case Kind::lead_hinge: return fmt::format("leadhinge:{}:{}", tau, level);
    case Kind::lag2: return fmt::format("lag2:{}:{}", tau, tau2);
    case Kind::lag2_rate: return fmt::format("lag2rate:{}:{}", tau, tau2);
    case Kind::node_hinge: return fmt::format("nodehinge:{}:{}:{}:{}", tau, tau2, zero, level);
    case Kind::play: return fmt::format("play:{}:{}", tau, level);
    case Kind::turn_on: return fmt::format("on:{}", tau);
  }
  return "?";
}

FeatureTerm FeatureTerm::parse(const std::string& text) {
  FeatureTerm term;
  for (const std::string_view factor_text : split(text, '*')) {
    const auto pieces = split(factor_text, '^');
    if (pieces.size() > 2) bad_term(text, "one power per factor");
    FeatureFactor factor{parse_atom(text, pieces[0]), 1};
    if (pieces.size() == 2) {
      if (pieces[1].size() != 1 || pieces[1][0] < '1' || pieces[1][0] > '0' + kMaxPower) {
        bad_term(text, fmt::format("power '{}' must be 1..{}", pieces[1], kMaxPower));
      }
      factor.power = pieces[1][0] - '0';
    }
    term.factors.push_back(factor);
  }
  if (term.uses_input() && !(term.factors.size() == 1 && term.factors[0].power == 1)) {
    bad_term(text, "libsvm columns xN are used as given, not in products or powers");
  }
  return term;
}

std::string FeatureTerm::name() const {
  std::string text;
  for (const auto& factor : factors) {
    if (!text.empty()) text += '*';
    text += factor.atom.name();
    if (factor.power != 1) text += fmt::format("^{}", factor.power);
  }
  return text;
}

bool FeatureTerm::has(Kind kind) const {
  return std::any_of(factors.begin(), factors.end(), [kind](const FeatureFactor& factor) { return factor.atom.kind == kind; });
}

std::vector<double> FeatureTerm::time_constants() const {
  std::vector<double> out;
  for (const auto& factor : factors) {
    if (factor.atom.tau > 0) out.push_back(factor.atom.tau);
    if (factor.atom.tau2 > 0) out.push_back(factor.atom.tau2);
    if (factor.atom.zero > 0) out.push_back(factor.atom.zero);
  }
  return out;
}

std::vector<std::size_t> FeatureTerm::channels() const {
  std::vector<std::size_t> out;
  for (const auto& factor : factors) {
    if (factor.atom.reads_channels()) {
      out.push_back(factor.atom.channel);
      out.push_back(factor.atom.channel2);
    }
  }
  return out;
}

double lag_step(double state, double input, double step_seconds, double tau) {
  if (!(step_seconds > 0)) return input;
  const double a = std::exp(-step_seconds / tau);
  return a * state + (1.0 - a) * input;
}

double TermEvaluator::lag(Filter& filter, double input, double step_seconds, double tau) const {
  if (hold_ == InputHold::step) {
    if (!(step_seconds > 0)) return filter.value = input;
    if (step_seconds != filter.step) filter.step = step_seconds, filter.decay = std::exp(-step_seconds / tau);
    return filter.value = filter.decay * filter.value + (1.0 - filter.decay) * input;
  }
  // The input a straight line from u0 to u1 over the step h, read d = lead_seconds_ ahead:
  // the exact output is a·y0 + (1 - a)·u1 + (u1 - u0)·(a - (1 - a)·(τ - d)/h), a = exp(-h/τ).
  const double last = filter.input;
  filter.input = input;
  if (!(step_seconds > 0)) return filter.value = input;
  if (step_seconds != filter.step) {
    filter.step = step_seconds, filter.decay = std::exp(-step_seconds / tau);
    filter.ramp = filter.decay - (1.0 - filter.decay) * (tau - lead_seconds_) / step_seconds;
  }
  return filter.value = filter.decay * filter.value + (1.0 - filter.decay) * input + filter.ramp * (input - last);
}

namespace {

// The time constant of an atom's first filter when that is a lag of ΔT (0: it has none).
double first_lag_tau(const FeatureAtom& atom) {
  using Kind = FeatureAtom::Kind;
  switch (atom.kind) {
    case Kind::lag:
    case Kind::lag_rate:
    case Kind::gradient_rate:
    case Kind::hinge:
    case Kind::lag2:
    case Kind::lag2_rate:
    case Kind::node_hinge:
    case Kind::play: return atom.tau;
    case Kind::direction: return atom.tau2;
    default: return 0;
  }
}

// Whether an atom's second filter is the lag (tau2) of its first.
bool lags_its_lag(const FeatureAtom& atom) {
  using Kind = FeatureAtom::Kind;
  return (atom.kind == Kind::lag2 || atom.kind == Kind::lag2_rate || atom.kind == Kind::node_hinge) && atom.tau2 > 0;
}

}  // namespace

TermEvaluator::TermEvaluator(const std::vector<FeatureTerm>& terms, InputHold hold, double lead_seconds)
    : terms_(&terms), hold_(hold), lead_seconds_(lead_seconds) {
  std::vector<const FeatureAtom*>& atoms = atoms_;
  for (const auto& term : terms) {
    for (const auto& factor : term.factors) atoms.push_back(&factor.atom);
  }
  states_.resize(atoms.size());
  first_owner_.resize(atoms.size());
  second_owner_.resize(atoms.size());
  for (std::size_t s = 0; s < atoms.size(); ++s) {
    first_owner_[s] = second_owner_[s] = s;
    const double tau = first_lag_tau(*atoms[s]);
    for (std::size_t o = 0; o < s && tau > 0; ++o) {
      if (first_lag_tau(*atoms[o]) != tau) continue;
      if (first_owner_[s] == s) first_owner_[s] = o;
      if (lags_its_lag(*atoms[s]) && lags_its_lag(*atoms[o]) && atoms[o]->tau2 == atoms[s]->tau2) {
        second_owner_[s] = o;
        break;
      }
    }
  }
  using Kind = FeatureAtom::Kind;
  for (std::size_t s = 0; s < atoms.size(); ++s) {
    const FeatureAtom& atom = *atoms[s];
    const bool own_first = first_lag_tau(atom) > 0 && first_owner_[s] == s;
    const bool own_second = atom.kind == Kind::gradient_rate || atom.kind == Kind::play || atom.kind == Kind::direction ||
                            atom.kind == Kind::turn_on || (lags_its_lag(atom) && second_owner_[s] == s);
    if (own_first || own_second) stateful_.push_back(s);
  }
}

void TermEvaluator::advance(const TermInputs& inputs) {
  for (const std::size_t s : stateful_) atom_value(*atoms_[s], s, inputs);
}

double TermEvaluator::first_lag(std::size_t s, double delta_t, double step_seconds, double tau) {
  State& state = states_[s];
  const std::size_t owner = first_owner_[s];
  return owner == s ? lag(state.first, delta_t, step_seconds, tau) : states_[owner].first.value;
}

double TermEvaluator::atom_value(const FeatureAtom& atom, std::size_t s, const TermInputs& inputs) {
  using Kind = FeatureAtom::Kind;
  State& state = states_[s];
  const double delta_t = inputs.delta_t;
  const double step_seconds = inputs.step_seconds;
  switch (atom.kind) {
    case Kind::delta_t: return delta_t;
    case Kind::rate: return inputs.rate;
    case Kind::lag:
      return first_lag(s, delta_t, step_seconds, atom.tau);
    case Kind::lag_rate:
      return (delta_t - first_lag(s, delta_t, step_seconds, atom.tau)) / atom.tau * 60.0;
    case Kind::gradient_rate: {
      const double coil_rate = (delta_t - first_lag(s, delta_t, step_seconds, atom.tau)) / atom.tau * 60.0;
      return (coil_rate - lag(state.second, coil_rate, step_seconds, atom.tau2)) / atom.tau2 * 60.0;
    }
    case Kind::hinge:
      return std::max(0.0, first_lag(s, delta_t, step_seconds, atom.tau) - atom.level);
    case Kind::lead: return delta_t + atom.tau * inputs.rate / 60.0;
    case Kind::lead_hinge: return std::max(0.0, delta_t + atom.tau * inputs.rate / 60.0 - atom.level);
    case Kind::lag2:
    case Kind::lag2_rate:
    case Kind::node_hinge: {
      const double first = first_lag(s, delta_t, step_seconds, atom.tau);
      double second = 0;
      if (atom.tau2 > 0) {
        const std::size_t owner = second_owner_[s];
        second = owner == s ? lag(state.second, first, step_seconds, atom.tau2) : states_[owner].second.value;
      }
      if (atom.kind == Kind::lag2) return second;
      if (atom.kind == Kind::lag2_rate) return (first - second) / atom.tau2 * 60.0;
      const double node = atom.tau2 > 0 ? second + atom.zero * (first - second) / atom.tau2
                                        : first + atom.zero * (delta_t - first) / atom.tau;
      return std::max(0.0, node - atom.level);
    }
    case Kind::play: {
      const double first = first_lag(s, delta_t, step_seconds, atom.tau);
      double& played = state.second.value;
      if (!(step_seconds > 0)) played = first;  // equilibrium: nothing to catch up
      played = std::clamp(played, first - atom.level, first + atom.level);
      return (first - played) / atom.level;
    }
    case Kind::turn_on:
      // 1 at a (re)start, then a lag towards 0: exp(-t/TAU) exactly for any steps.
      return step_seconds > 0 ? lag(state.first, 0.0, step_seconds, atom.tau) : (state.first.value = 1.0);
    case Kind::direction: {
      double source = inputs.rate;
      if (atom.tau2 > 0) {
        source = (delta_t - first_lag(s, delta_t, step_seconds, atom.tau2)) / atom.tau2 * 60.0;
      }
      return lag(state.second, tanh_by_exp(source / atom.direction_rate_scale()), step_seconds, atom.tau);
    }
    case Kind::channel_gradient:
    case Kind::channel_gradient_rate: {
      const auto& values = atom.kind == Kind::channel_gradient ? inputs.channel_means : inputs.channel_rates;
      if (std::max(atom.channel, atom.channel2) >= values.size()) {
        throw UsageError(fmt::format("feature term '{}' reads temperature channel {}, but {} channel(s) are given",
                                     atom.name(), std::max(atom.channel, atom.channel2) + 1, values.size()));
      }
      return values[atom.channel] - values[atom.channel2];
    }
    case Kind::input: return 0;  // libsvm models never stream (Compensator refuses them)
  }
  return 0;
}

void TermEvaluator::push(const TermInputs& inputs, std::span<double> values) {
  std::size_t s = 0;
  for (std::size_t i = 0; i < terms_->size(); ++i) {
    double value = 1;
    for (const auto& factor : (*terms_)[i].factors) {
      const double atom = atom_value(factor.atom, s++, inputs);
      for (int p = 0; p < factor.power; ++p) value *= atom;
    }
    values[i] = value;
  }
}

}  // namespace thermodrift
