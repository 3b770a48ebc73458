// Each feature factor as C, and its cost per sample, in one switch over the kinds: a new
// kind of term is taught to the export here (and to terms.cpp, which defines it).
#include <fmt/format.h>

#include <algorithm>

#include "compensate/c_export_parts.hpp"
#include "thermodrift/error.hpp"

namespace thermodrift::c_export_detail {

FactorCode factor_code(const FeatureFactor& factor, const FactorPlace& place) {
  using Kind = FeatureAtom::Kind;
  const FeatureAtom& atom = factor.atom;
  const Literal literal(place.single_precision);
  const std::string& p = place.prefix;
  const std::string& s = place.state;
  auto slot_of = [&](std::size_t channel) {
    return static_cast<std::size_t>(std::find(place.channels.begin(), place.channels.end(), channel) -
                                    place.channels.begin());
  };
  auto advance_lag = [&] {
    return fmt::format("    {s}[0] = {p}_lag({s}[0], delta_t, {step}, {tau});\n", fmt::arg("s", s), fmt::arg("p", p),
                       fmt::arg("step", place.step), fmt::arg("tau", Literal::time(atom.tau)));
  };
  FactorCode code;
  switch (atom.kind) {
    case Kind::delta_t: code.value = "delta_t"; break;
    case Kind::rate: code.value = "rate"; break;
    case Kind::lag:
      code = {advance_lag(), s + "[0]", 1, 4};
      break;
    case Kind::hinge:
      code = {advance_lag(),
              fmt::format("({s}[0] > {k} ? {s}[0] - {k} : ({p}_real)0)", fmt::arg("s", s), fmt::arg("p", p),
                          fmt::arg("k", literal(atom.level))),
              1, 6};
      break;
    case Kind::lead:
      code = {"", fmt::format("(delta_t + {} * rate / ({}_real)60)", literal(atom.tau), p), 0, 3};
      break;
    case Kind::lead_hinge:
      code = {"",
              fmt::format("{p}_positive_part(delta_t + {tau} * rate / ({p}_real)60 - {k})", fmt::arg("p", p),
                          fmt::arg("tau", literal(atom.tau)), fmt::arg("k", literal(atom.level))),
              0, 5};
      break;
    case Kind::lag2:
    case Kind::lag2_rate:
    case Kind::node_hinge: {
      const int what = atom.kind == Kind::lag2 ? 0 : atom.kind == Kind::lag2_rate ? 1 : 2;
      code.value = fmt::format("{}_node({}, delta_t, {}, {}, {}, {}, {}, {})", p, s, place.step, Literal::time(atom.tau),
                               atom.tau2 > 0 ? Literal::time(atom.tau2) : std::string("0.0"),
                               atom.zero > 0 ? Literal::time(atom.zero) : std::string("0.0"), literal(atom.level), what);
      code.exps = atom.kind == Kind::node_hinge && atom.tau2 == 0 ? 1 : 2;
      code.flops = atom.kind == Kind::lag2 ? 8 : atom.kind == Kind::lag2_rate ? 11 : 14;
      break;
    }
    case Kind::play:
      code = {"", fmt::format("{}_play({}, delta_t, {}, {}, {})", p, s, place.step, Literal::time(atom.tau), literal(atom.level)),
              1, 10};
      break;
    case Kind::turn_on:
      code = {"", fmt::format("{}_turn_on({}, {}, {})", p, s, place.step, Literal::time(atom.tau)), 1, 4};
      break;
    case Kind::lag_rate:
      code = {"", fmt::format("{}_lag_rate(&{}[0], delta_t, {}, {})", p, s, place.step, Literal::time(atom.tau)), 1, 7};
      break;
    case Kind::gradient_rate:
      code = {"",
              fmt::format("{}_gradient_rate({}, delta_t, {}, {}, {})", p, s, place.step, Literal::time(atom.tau),
                          Literal::time(atom.tau2)),
              2, 14};
      break;
    case Kind::direction:
      code = {"",
              fmt::format("{}_direction({}, delta_t, rate, {}, {}, {}, {})", p, s, place.step, Literal::time(atom.tau),
                          Literal::time(atom.tau2), Literal::time(atom.direction_rate_scale())),
              atom.tau2 > 0 ? std::size_t{3} : std::size_t{2}, atom.tau2 > 0 ? std::size_t{14} : std::size_t{9}};
      break;
    case Kind::channel_gradient:
      code = {"", fmt::format("(channel_mean[{}] - channel_mean[{}])", slot_of(atom.channel), slot_of(atom.channel2)), 0, 1};
      break;
    case Kind::channel_gradient_rate:
      code = {"", fmt::format("(channel_rate[{}] - channel_rate[{}])", slot_of(atom.channel), slot_of(atom.channel2)), 0, 1};
      break;
    case Kind::input: throw UsageError("libsvm columns cannot be exported");  // refused before export
  }
  code.flops += static_cast<std::size_t>(factor.power);
  return code;
}

}  // namespace thermodrift::c_export_detail
