// The records of generalization_bench and what it prints of them: the table of ratios to
// the noise floor per method, test and axis, the fit times, the verdict against the
// targets, and the JSON of every law.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "thermodrift/models/model_kind.hpp"

namespace thermodrift::bench {

enum class Method {
  paper,     // SVR + AFSA on the paper's (dT, rate)
  linear,    // --features auto, least squares
  stepwise,  // --features auto, stepwise regression
  svr,       // --features auto, SVR + AFSA
  oracle,    // the law's own regressors on its true states, least squares: a bound, not a method
};

inline const char* to_string(Method method) {
  switch (method) {
    case Method::paper: return "paper";
    case Method::linear: return "linear";
    case Method::stepwise: return "stepwise";
    case Method::svr: return "svr";
    case Method::oracle: return "oracle";
  }
  return "paper";
}

inline Method parse_method(const std::string& name) {
  for (Method method : {Method::paper, Method::linear, Method::stepwise, Method::svr, Method::oracle}) {
    if (name == to_string(method)) return method;
  }
  throw std::invalid_argument(fmt::format("unknown method '{}' (paper, linear, stepwise, svr or oracle)", name));
}

// The calibrate model of a method.
// The model kind a method fits (the oracle: least squares, as linear).
inline thermodrift::ModelKind model_kind(Method method) {
  switch (method) {
    case Method::paper:
    case Method::svr: return thermodrift::ModelKind::svr;
    case Method::stepwise: return thermodrift::ModelKind::stepwise;
    default: return thermodrift::ModelKind::linear;
  }
}

inline std::string method_list(const std::vector<Method>& methods) {
  std::string list;
  for (Method method : methods) list += fmt::format("{}{}", list.empty() ? "" : ",", to_string(method));
  return list;
}

// The name of the diagnostic test: the next cycle with the lags carried over (not a target).
inline const std::string carried_test = "next cycle, carried";
inline bool is_profile(const std::string& test) { return test != "next cycle" && test != carried_test; }

struct Cost {
  double cpu_s = 0;   // of the thread that ran it
  double wall_s = 0;
};

struct TestResult {
  std::array<double, 3> mse{};    // held-out MSE after compensation, (°/h)²
  std::array<double, 3> floor{};  // the true noise floor of the same rows, (°/h)²
  std::array<double, 3> ratio{};  // mse / floor
  // MSE of the prediction against the smoothed true drift (no noise) over the floor: how far
  // the model is from the unit's drift there, the noise left out (simulated logs only).
  std::array<double, 3> distance{};
};

struct MethodResult {
  Method method = Method::paper;
  Cost fit;     // calibrate, for the auto methods given the shared search
  Cost search;  // the shared least-squares search (auto methods; zero for paper)
  std::array<double, 3> in_sample{};  // in-sample MSE / the training cycle's floor
  std::array<double, 3> training_distance{};  // TestResult::distance on the training cycle's rows
  std::array<std::vector<std::string>, 3> terms;
  std::array<std::size_t, 3> temperature_channel{};  // 1-based channel of the axis' node; 0: its own
  // --node-channel any: per axis, each channel's node as the search scored it: {channel,
  // single lag's CV MSE, whole node's CV MSE}
  std::array<std::vector<std::array<double, 3>>, 3> channel_scores;
  std::vector<TestResult> tests;  // in LawResult::tests order
  std::string error;              // calibrate or evaluate threw: every ratio counts as infinite

  Cost total() const { return {fit.cpu_s + search.cpu_s, fit.wall_s + search.wall_s}; }
  double ratio(std::size_t test, std::size_t axis) const {
    return error.empty() ? tests.at(test).ratio[axis] : std::numeric_limits<double>::infinity();
  }
  // Over the tests (`names`: LawResult::tests), the carried diagnostic left out.
  double worst(const std::vector<std::string>& names) const {
    double worst = error.empty() ? 0.0 : std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < tests.size(); ++t) {
      if (names.at(t) != carried_test) worst = std::max({worst, tests[t].ratio[0], tests[t].ratio[1], tests[t].ratio[2]});
    }
    return worst;
  }
};

struct LawResult {
  std::uint64_t seed = 0;
  std::vector<std::string> tests;  // "next cycle", the two other profiles' kinds, carried_test
  Cost search;
  Cost cost;  // the whole law: simulation, search, fits, evaluation
  double training_s = 0;  // length of the training log(s)
  std::array<double, 3> training_floor{};  // the true noise floor of the (first) training log
  double air_rate_intensity = 0;  // --oracle-states measured: the filter's, chosen on the training cycle
  std::vector<MethodResult> methods;
};

inline std::string progress_line(const LawResult& law) {
  std::string line = fmt::format("law {}: {:.1f} s (cpu {:.1f} s); worst ratio", law.seed, law.cost.wall_s, law.cost.cpu_s);
  for (const auto& method : law.methods) {
    line += fmt::format(" {} {:.2f}{}", to_string(method.method), method.worst(law.tests), method.error.empty() ? "" : " (failed)");
  }
  return line + fmt::format(" [other profiles: {}, {}]", law.tests.at(1), law.tests.at(2));
}

// One ratio with the law it came from.
struct Sample {
  double value = 0;
  std::uint64_t seed = 0;
};

// Type-7 quantile (linear between order statistics) of values sorted ascending.
inline double quantile(const std::vector<Sample>& sorted, double p) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double position = p * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  const double low = sorted[below].value, high = sorted[above].value;
  if (std::isinf(low) || std::isinf(high)) return position == static_cast<double>(below) ? low : high;
  return low + (position - static_cast<double>(below)) * (high - low);
}

struct Distribution {
  std::size_t count = 0;
  double median = 0, p90 = 0;
  Sample worst;
};

inline Distribution describe(std::vector<Sample> samples) {
  std::sort(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) { return a.value < b.value; });
  Distribution d;
  d.count = samples.size();
  if (samples.empty()) return d;
  d.median = quantile(samples, 0.5);
  d.p90 = quantile(samples, 0.9);
  d.worst = samples.back();
  return d;
}

// A ratio in six characters: two decimals near the targets, fewer for a blow-up.
inline std::string ratio_text(double ratio) {
  if (!(ratio < 100)) return fmt::format("{:6.0f}", ratio);
  return ratio < 10 ? fmt::format("{:6.2f}", ratio) : fmt::format("{:6.1f}", ratio);
}

// Targets per axis and test group: median <= 2, p90 <= 4, worst <= 10 times the floor.
// Returns the statistics that miss theirs ("median,p90"), empty when all are met.
inline std::string misses(const Distribution& d) {
  std::string missed;
  auto add = [&](bool met, const char* what) {
    if (!met) missed += fmt::format("{}{}", missed.empty() ? "" : ",", what);
  };
  add(d.median <= 2, "median");
  add(d.p90 <= 4, "p90");
  add(d.worst.value <= 10, "worst");
  return missed;
}

inline std::string summary_table(const std::vector<LawResult>& laws, const std::vector<Method>& methods) {
  static constexpr std::array<const char*, 3> axis_names = {"x", "y", "z"};
  std::string out;
  if (laws.empty()) return "no law finished\n";
  std::string seeds;
  for (const auto& law : laws) seeds += fmt::format("{}{}", seeds.empty() ? "" : ",", law.seed);
  out += fmt::format("laws ({}): {}\n\n", laws.size(), seeds);

  // Test groups: the next cycle, the other profiles pooled, each kind on its own, and the
  // carried diagnostic.
  std::vector<std::string> groups{"next cycle", "other profiles"};
  std::map<std::string, bool> kinds;
  for (const auto& law : laws) {
    for (const auto& test : law.tests) {
      if (is_profile(test)) kinds[test] = true;
    }
  }
  for (const auto& [kind, unused] : kinds) groups.push_back(kind);
  groups.push_back(carried_test);
  auto in_group = [](const std::string& group, const std::string& test) {
    return group == "other profiles" ? is_profile(test) : test == group;
  };

  out += "held-out MSE / noise floor, per axis: median  p90  worst (law); \"" + carried_test +
         "\": cycle 2 with the lags carried from cycle 1 (a diagnostic, not a target)\n";
  out += fmt::format("{:<9} {:<19} {:>4}", "method", "test", "n");
  for (const char* axis : axis_names) out += fmt::format(" | {}: {:>6} {:>6} {:>6} {:>6}", axis, "median", "p90", "worst", "(law)");
  out += "\n";
  std::map<Method, std::vector<std::string>> verdict;
  for (Method method : methods) {
    for (const auto& group : groups) {
      std::array<Distribution, 3> axes;
      for (std::size_t a = 0; a < 3; ++a) {
        std::vector<Sample> samples;
        for (const auto& law : laws) {
          for (const auto& result : law.methods) {
            if (result.method != method) continue;
            for (std::size_t t = 0; t < law.tests.size(); ++t) {
              if (in_group(group, law.tests[t])) samples.push_back({result.ratio(t, a), law.seed});
            }
          }
        }
        axes[a] = describe(std::move(samples));
        const std::string missed = misses(axes[a]);
        if ((group == "next cycle" || group == "other profiles") && !missed.empty()) {
          verdict[method].push_back(fmt::format("{} {}: {}", group, axis_names[a], missed));
        }
      }
      out += fmt::format("{:<9} {:<19} {:>4}", to_string(method), group, axes[0].count);
      for (const auto& d : axes) {
        out += fmt::format(" |    {} {} {} {:>6}", ratio_text(d.median), ratio_text(d.p90), ratio_text(d.worst.value),
                           fmt::format("({})", d.worst.seed));
      }
      out += "\n";
    }
  }

  // One figure per method and test group over every law and axis, to compare two runs by:
  // the geometric mean of the ratios (the mean of their logs: a law 100x worse counts as
  // much as one 100x better) and how many exceed 10 and 100.
  out += "\nall axes together: geometric mean of the ratios; ratios above 10 and above 100 (of n)\n";
  for (Method method : methods) {
    std::string line = fmt::format("{:<9}", to_string(method));
    for (const std::string group : {"next cycle", "other profiles"}) {
      double log_sum = 0;
      std::size_t n = 0, above_10 = 0, above_100 = 0;
      for (const auto& law : laws) {
        for (const auto& result : law.methods) {
          if (result.method != method || !result.error.empty()) continue;
          for (std::size_t t = 0; t < law.tests.size(); ++t) {
            if (!in_group(group, law.tests[t])) continue;
            for (std::size_t a = 0; a < 3; ++a) {
              const double ratio = result.ratio(t, a);
              if (!(ratio > 0) || !std::isfinite(ratio)) continue;
              log_sum += std::log(ratio);
              ++n;
              above_10 += ratio > 10;
              above_100 += ratio > 100;
            }
          }
        }
      }
      line += n == 0 ? fmt::format(" | {}: none", group)
                     : fmt::format(" | {}: {:.2f}, > 10: {}, > 100: {} (of {})", group,
                                   std::exp(log_sum / static_cast<double>(n)), above_10, above_100, n);
    }
    out += line + "\n";
  }

  out += "\nin-sample MSE / floor of the training cycle (in-sample: optimistic), median per axis; fit time per law\n";
  out += "(fit = calibrate; for linear, stepwise and svr plus the whole shared least-squares search, counted once in each;\n"
         " cpu = CPU seconds of the law's thread, tuning on one thread; wall on a shared machine)\n";
  out += fmt::format("{:<9} {:>6} {:>6} {:>6} | {:>9} {:>17} | {:>9} {:>9} | {:>10} | {}\n", "method", "x", "y", "z",
                     "cpu med", "cpu worst (law)", "wall med", "wall max", "search med", "failed");
  for (Method method : methods) {
    std::array<std::vector<Sample>, 3> in_sample;
    std::vector<Sample> cpu, wall, search;
    std::size_t failed = 0;
    for (const auto& law : laws) {
      for (const auto& result : law.methods) {
        if (result.method != method) continue;
        if (!result.error.empty()) ++failed;
        for (std::size_t a = 0; a < 3; ++a) in_sample[a].push_back({result.error.empty() ? result.in_sample[a] : NAN, law.seed});
        cpu.push_back({result.total().cpu_s, law.seed});
        wall.push_back({result.total().wall_s, law.seed});
        search.push_back({result.search.cpu_s, law.seed});
      }
    }
    const Distribution c = describe(cpu), w = describe(wall), s = describe(search);
    out += fmt::format("{:<9} {:6.2f} {:6.2f} {:6.2f} | {:9.1f} {:9.1f} ({:>5}) | {:9.1f} {:9.1f} | {:10.1f} | {}\n",
                       to_string(method), describe(in_sample[0]).median, describe(in_sample[1]).median,
                       describe(in_sample[2]).median, c.median, c.worst.value, c.worst.seed, w.median,
                       w.worst.value, s.median, failed);
  }

  out += "\ntargets per axis, on the next cycle and on the other profiles: median <= 2, p90 <= 4, worst <= 10\n";
  for (Method method : methods) {
    const auto& missed = verdict[method];
    std::string reasons;
    for (const auto& miss : missed) reasons += fmt::format("{}{}", reasons.empty() ? "" : "; ", miss);
    out += fmt::format("{:<9} {}{}\n", to_string(method), missed.empty() ? "PASS" : "FAIL",
                       missed.empty() ? "" : fmt::format(" ({} of 6 test-axes miss: {})", missed.size(), reasons));
  }
  return out;
}

inline nlohmann::json laws_json(const std::vector<LawResult>& laws) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& law : laws) {
    nlohmann::json methods = nlohmann::json::array();
    for (const auto& result : law.methods) {
      nlohmann::json entry = {{"method", to_string(result.method)},
                              {"fit_cpu_s", result.fit.cpu_s},
                              {"fit_wall_s", result.fit.wall_s},
                              {"search_cpu_s", result.search.cpu_s},
                              {"search_wall_s", result.search.wall_s}};
      if (!result.error.empty()) {
        entry["error"] = result.error;
      } else {
        nlohmann::json tests = nlohmann::json::array();
        for (std::size_t t = 0; t < result.tests.size(); ++t) {
          const auto& test = result.tests[t];
          tests.push_back({{"test", law.tests[t]}, {"mse_after", test.mse}, {"floor", test.floor}, {"ratio", test.ratio},
                          {"distance", test.distance}});
        }
        entry["in_sample_ratio"] = result.in_sample;
        entry["training_distance"] = result.training_distance;
        entry["terms"] = result.terms;
        entry["temperature_channel"] = result.temperature_channel;
        if (!result.channel_scores[0].empty()) entry["channel_scores"] = result.channel_scores;
        entry["tests"] = tests;
      }
      methods.push_back(entry);
    }
    out.push_back({{"seed", law.seed}, {"tests", law.tests}, {"cpu_s", law.cost.cpu_s}, {"wall_s", law.cost.wall_s},
                   {"training_s", law.training_s}, {"training_floor", law.training_floor},
                   {"air_rate_intensity", law.air_rate_intensity},
                   {"methods", methods}});
  }
  return out;
}

}  // namespace thermodrift::bench
