// Feature terms: what a drift model sees of an axis' temperature history. Every term is
// causal: its value at t depends on samples at or before t only, so the model fitted in
// the lab runs unchanged on the device.
//
// Atoms, computed from the smoothed temperature T_s (ΔT = T_s - reference):
//   dT               ΔT, °C                                                (paper)
//   rate             (T_s(t) - T_s(t - span)) / span, °C/min                (paper)
//   lag:TAU          L, a first-order lag of ΔT:  TAU·dL/dt = ΔT - L, °C    (coil temperature)
//   lagrate:TAU      dL/dt = (ΔT - L)/TAU, °C/min                           (coil rate; its gap to
//                    the sensor, ΔT - L, is TAU times this)
//   gradrate:TAU:TG  the rate of G, a lag (TG) of lagrate:TAU: (lagrate - G)/TG, °C/min²
//                    (the Shupe term: the radial gradient follows the coil rate with a lag)
//   dir:TAU[:LAG[:R0]]  a lag (TAU) of tanh(r / R0), r the smoothed rate (LAG absent or 0) or
//                    lagrate:LAG, R0 in °C/min (default 0.2): a heating (+1) / cooling (-1)
//                    memory, unitless; rates well above R0 saturate it
//   grad:A-B         T_A - T_B, the difference of two smoothed temperature channels, °C
//                    (A, B: 1-based channel numbers in the log's --temp order; a gradient
//                    across the unit, say housing minus chamber or coil minus mount)
//   gradrate:A-B     its rate, the backward difference over the rate span, °C/min
//   hinge:TAU:K      max(0, L - K), L = lag:TAU, K in °C of ΔT: with lag:TAU and several knots K, a
//                    piecewise-linear static map of the node temperature (linear beyond the last
//                    knots, so it extrapolates along the slopes it was fitted with)
//   lead:TAU         ΔT + TAU·rate, °C: a node the sensor lags by TAU (a sensor deeper in the unit
//                    than the coil: on another axis' block, or on a massive mount)
//   leadhinge:TAU:K  max(0, lead:TAU - K): the piecewise-linear map of such a node
//   lag2:T1:T2       L2, a lag (T2) of L1 = lag:T1: the coil two thermal nodes behind the sensor, °C
//   lag2rate:T1:T2   dL2/dt = (L1 - L2)/T2, °C/min
//   nodehinge:T1:T2:TL:K  max(0, N - K), N = L2 + TL·dL2/dt (T2 > 0) or L1 + TL·dL1/dt (T2 = 0):
//                    the static map of a node with two poles and a zero, N = (1 + s·TL) /
//                    ((1 + s·T1)(1 + s·T2)) ΔT, which holds a coil two nodes behind the sensor
//                    (TL = 0) and one on another thermal path than the sensor's (TL > 0: the
//                    sensor lags the common source by TL, the coil by T1). N itself is linear in
//                    lag2 and lag2rate (or lag and lagrate), so only its hinges need an atom.
//   play:TAU:W       (L - P)/W, L = lag:TAU and P the play (backlash) operator on it with half-width
//                    W °C: P stays put while |L - P| < W and is dragged along at W behind L
//                    beyond; unitless in [-1, 1]. A hysteresis set by how far the temperature
//                    moved since it last turned, whatever the rate (dir's memory is set by
//                    the rate and how long it lasted)
//   on:TAU           exp(-t/TAU), t the time since the stream's (re)start, unitless: 1 at power-on,
//                    0 long after; a turn-on transient (the gyro's own, and its self-heating
//                    settling through the unit), as a compensator started at power-on sees it
//   xN               column N of libsvm-format data, as given (never streamed)
// A term is one atom or a product of atoms with powers: "dT^2", "dT*rate", "lag:600^2*rate".
//
// Lags start in equilibrium (L = ΔT, G = lagrate, the memory at its input) at the first
// sample and after every gap; each step is exact for an input held over the step:
// L ← a·L + (1 - a)·ΔT, a = exp(-dt/TAU).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace thermodrift {

// r0 of dir when the term does not give one: rates well above it (ramps) saturate the
// indicator, soaks bring it to 0.
inline constexpr double kDirectionRateScale = 0.2;  // °C/min

// Channels a grad term can name: enough for every sensor of a multi-gyro unit.
inline constexpr std::size_t kMaxTemperatureChannels = 64;

struct FeatureAtom {
  enum class Kind { delta_t, rate, lag, lag_rate, gradient_rate, direction, input, channel_gradient,
                    channel_gradient_rate, hinge, lead, lead_hinge, lag2, lag2_rate, node_hinge, play,
                    turn_on };
  Kind kind = Kind::delta_t;
  double tau = 0;               // s: lag, lagrate, gradrate (first lag), dir (memory), on (decay)
  double tau2 = 0;              // s: gradrate (gradient lag); dir (lag of its rate, 0: smoothed rate)
  std::size_t input_index = 0;  // 0-based column, for Kind::input
  std::size_t channel = 0;      // 0-based temperature channels A and B of grad / gradrate:A-B
  std::size_t channel2 = 0;
  double level = 0;             // °C of ΔT: the knot of hinge:TAU:K; the half-width W of play:TAU:W
  double zero = 0;              // s: TL of nodehinge (0: none)
  double rate_scale = 0;        // °C/min: R0 of dir (0: kDirectionRateScale)

  double direction_rate_scale() const { return rate_scale > 0 ? rate_scale : kDirectionRateScale; }

  bool reads_channels() const { return kind == Kind::channel_gradient || kind == Kind::channel_gradient_rate; }

  std::string name() const;
  bool operator==(const FeatureAtom&) const = default;
};

struct FeatureFactor {
  FeatureAtom atom;
  int power = 1;  // 1..4
  bool operator==(const FeatureFactor&) const = default;
};

struct FeatureTerm {
  using Kind = FeatureAtom::Kind;
  std::vector<FeatureFactor> factors;

  FeatureTerm() = default;
  explicit FeatureTerm(FeatureAtom atom) : factors{{atom, 1}} {}
  explicit FeatureTerm(Kind kind) : FeatureTerm(FeatureAtom{kind}) {}

  // UsageError naming the term and what was expected.
  static FeatureTerm parse(const std::string& text);
  std::string name() const;
  // The kind of a plain atom (one factor, power 1); Kind::input also for libsvm columns.
  bool is_atom(Kind kind) const { return factors.size() == 1 && factors[0].power == 1 && factors[0].atom.kind == kind; }
  // Whether any factor is an atom of `kind`.
  bool has(Kind kind) const;
  bool uses_input() const { return has(Kind::input); }
  // The time constants (s) of its atoms, in order, with repeats.
  std::vector<double> time_constants() const;
  // The temperature channels (0-based) its grad atoms read, in order, with repeats.
  std::vector<std::size_t> channels() const;
  bool operator==(const FeatureTerm&) const = default;
};

// What the terms of one sample are computed from.
struct TermInputs {
  double delta_t = 0;       // ΔT of the axis' smoothed temperature, °C
  double rate = 0;          // its rate, °C/min
  double step_seconds = 0;  // since the previous sample; 0 at a (re)start: lags set in equilibrium
  // Smoothed temperature and rate (°C, °C/min) of each channel, indexed by channel number;
  // only the channels the grad terms read need to hold values.
  std::span<const double> channel_means;
  std::span<const double> channel_rates;
};

// How a filter's input moves between two samples: held at the newer sample's value (the
// streaming runtime's rule, exact for a log sampled as it is recorded) or along a straight
// line from the older to the newer (exact for a piecewise-linear input, so that a smooth
// input sampled sparsely is filtered as if it had been sampled densely: the feature
// searches' columns on the decimated rows, sparse_inputs).
enum class InputHold { step, linear };

// The streaming state of a list of terms: two filter states per factor, no allocation
// after construction.
class TermEvaluator {
 public:
  // `lead_seconds`, with the linear hold: the line is read that far ahead of each sample.
  // Half a dense step makes sparse samples filter as the step hold over the dense ones does
  // (which leads a ramp by half its step), to within step²/(12·τ) seconds of lag.
  explicit TermEvaluator(const std::vector<FeatureTerm>& terms, InputHold hold = InputHold::step,
                         double lead_seconds = 0);

  // One sample; writes one value per term. A grad term whose channel is not in the
  // inputs is a UsageError.
  void push(const TermInputs& inputs, std::span<double> values);
  // One sample whose values are not wanted: only the filters that carry state from sample
  // to sample are stepped (a node's hinges, level and rate are read off its one filter at
  // the next push). The values of later pushes are the same, bit for bit.
  void advance(const TermInputs& inputs);
  // The same for terms that read no temperature channel but the axis' own.
  void push(double delta_t, double rate, double step_seconds, std::span<double> values) {
    push(TermInputs{delta_t, rate, step_seconds, {}, {}}, values);
  }

 private:
  // A first-order lag: its output, exp(-step/τ) for the last step length (a log of even
  // steps needs one exp per filter, not one per sample), and for a linear hold the weight
  // of the input's change over the step and the last input.
  struct Filter {
    double value = 0;
    double step = -1, decay = 0, ramp = 0;
    double input = 0;
  };
  struct State {
    Filter first;   // L, the lag of ΔT (lag, lagrate, gradrate, dir with LAG); L1 of lag2; on's value
    Filter second;  // G (gradrate), the direction memory (dir), L2 (lag2, lag2rate, nodehinge) or P (play)
  };
  // Steps `filter` by one sample of `input` (step 0: equilibrium, the output is the input).
  // With the step hold, lag_step's arithmetic with the decay memoized: the same bits.
  double lag(Filter& filter, double input, double step_seconds, double tau) const;
  // Factor s's first filter (the lag of ΔT), stepped by the first factor that has the same
  // one and copied by the others: a node's level, hinges and rate share one filter.
  double first_lag(std::size_t s, double delta_t, double step_seconds, double tau);
  double atom_value(const FeatureAtom& atom, std::size_t s, const TermInputs& inputs);

  const std::vector<FeatureTerm>* terms_;
  InputHold hold_;
  double lead_seconds_;
  std::vector<State> states_;  // one per factor, in order
  // Per factor: the factor that steps its first filter, and (lag2, lag2rate, nodehinge with
  // a second lag) its second; itself when no earlier factor has the same filter.
  std::vector<std::size_t> first_owner_, second_owner_;
  std::vector<const FeatureAtom*> atoms_;  // per factor
  std::vector<std::size_t> stateful_;      // the factors advance steps
};

// First-order lag update exact for an input held over the step; `step_seconds` 0 sets
// the state to the input (equilibrium). The evaluator steps its filters by the same
// arithmetic (with exp memoized per filter); its tests use this one.
double lag_step(double state, double input, double step_seconds, double tau);

}  // namespace thermodrift
