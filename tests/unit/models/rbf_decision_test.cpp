// The decision function's vectorised RBF sums against the formula written out: the
// exact sum (fits) and every variant of the field's sum this CPU runs, for every
// remainder of the lanes (counts 0-40) and feature counts on both sides of the
// stack-array limit (1-40); and their exp over the whole range an RBF kernel reaches.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "models/svr_kernel.hpp"
#include "thermodrift/models/svr.hpp"

namespace thermodrift {
namespace {

struct Case {
  RbfDecisionFunction function;
  std::vector<double> x;
  long double expected = 0;  // the formula in long double
  double magnitude = 0;      // |bias| + Σ|coefficients|
};

Case random_case(std::mt19937_64& generator, int features, int count) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Case c;
  RbfDecisionFunction& function = c.function;
  function.gamma = 0.3 / features;
  function.bias = normal(generator);
  function.support_vectors.resize(count, features);
  function.coefficients.resize(count);
  for (int k = 0; k < count; ++k) {
    function.coefficients(k) = 10 * normal(generator);
    for (int f = 0; f < features; ++f) function.support_vectors(k, f) = normal(generator);
  }
  c.x.resize(static_cast<std::size_t>(features));
  for (auto& value : c.x) value = normal(generator);
  c.expected = function.bias;
  c.magnitude = std::abs(function.bias);
  for (int k = 0; k < count; ++k) {
    long double squared = 0;
    for (int f = 0; f < features; ++f) {
      const long double d = static_cast<long double>(function.support_vectors(k, f)) - c.x[static_cast<std::size_t>(f)];
      squared += d * d;
    }
    c.expected += function.coefficients(k) * std::exp(-static_cast<long double>(function.gamma) * squared);
    c.magnitude += std::abs(function.coefficients(k));
  }
  return c;
}

TEST(RbfDecisionFunction, VectorisedSumMatchesTheFormula) {
  std::mt19937_64 generator(3);
  for (int features : {1, 2, 7, 33, 40}) {
    for (int count = 0; count <= 40; ++count) {
      const Case c = random_case(generator, features, count);
      EXPECT_NEAR(c.function(c.x.data()), static_cast<double>(c.expected), 1e-15 * c.magnitude)
          << features << " features, " << count << " vectors";
      EXPECT_NEAR(c.function.fast(c.x.data()), static_cast<double>(c.expected), 1e-15 * c.magnitude)
          << features << " features, " << count << " vectors";
    }
  }
}

TEST(RbfDecisionFunction, EveryFieldVariantOfThisCpuMatchesTheFormula) {
  const auto variants = svr_detail::rbf_sum_variants();
  ASSERT_FALSE(variants.empty());
  EXPECT_STREQ(variants.back().name, "exact");
  for (const auto& variant : variants) {
    std::mt19937_64 generator(5);
    double worst = 0;
    for (int features : {1, 2, 3, 7, 33}) {
      for (int count = 0; count <= 40; ++count) {
        const Case c = random_case(generator, features, count);
        const auto& sv = c.function.support_vectors;
        std::vector<const double*> columns;
        for (Eigen::Index f = 0; f < sv.cols(); ++f) columns.push_back(sv.col(f).data());
        const double sum = c.function.bias + variant.sum(columns.data(), columns.size(), c.x.data(), c.function.gamma,
                                                         c.function.coefficients.data(), static_cast<std::size_t>(count));
        worst = std::max(worst, std::abs(sum - static_cast<double>(c.expected)) / c.magnitude);
      }
    }
    EXPECT_LT(worst, 1e-15) << variant.name;
  }
}

// One vector at 0 with coefficient 1 and γ = 1: the sum at x = √t is exp(−t) itself.
TEST(RbfDecisionFunction, EveryVariantsExpIsAccurateOverTheKernelsRange) {
  const double vector = 0, coefficient = 1;
  const double* columns[1] = {&vector};
  for (const auto& variant : svr_detail::rbf_sum_variants()) {
    double worst = 0;
    for (double t = 0; t <= 760; t += 0.0137) {
      const double x = std::sqrt(t);
      const double squared = x * x;  // what the sum computes
      const double value = variant.sum(columns, 1, &x, 1.0, &coefficient, 1);
      const long double expected = std::exp(-static_cast<long double>(squared));
      if (squared > 708) {
        EXPECT_LE(value, 1e-307) << variant.name << " at " << squared;
        EXPECT_GE(value, 0.0) << variant.name << " at " << squared;
        continue;
      }
      worst = std::max(worst, static_cast<double>(std::abs(value - expected) / expected));
    }
    EXPECT_LT(worst, 4e-16) << variant.name;
  }
}

}  // namespace
}  // namespace thermodrift
