// The decision function's vectorised RBF sum against the formula written out, for every
// remainder of the lanes (counts 0-19) and feature counts on both sides of the
// stack-array limit (1-40).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "thermodrift/models/svr.hpp"

namespace thermodrift {
namespace {

TEST(RbfDecisionFunction, VectorisedSumMatchesTheFormula) {
  std::mt19937_64 generator(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int features : {1, 2, 7, 33, 40}) {
    for (int count = 0; count < 20; ++count) {
      RbfDecisionFunction function;
      function.gamma = 0.3 / features;
      function.bias = normal(generator);
      function.support_vectors.resize(count, features);
      function.coefficients.resize(count);
      for (int k = 0; k < count; ++k) {
        function.coefficients(k) = 10 * normal(generator);
        for (int f = 0; f < features; ++f) function.support_vectors(k, f) = normal(generator);
      }
      std::vector<double> x(static_cast<std::size_t>(features));
      for (auto& value : x) value = normal(generator);
      double expected = function.bias, magnitude = std::abs(function.bias);
      for (int k = 0; k < count; ++k) {
        double squared = 0;
        for (int f = 0; f < features; ++f) squared += std::pow(function.support_vectors(k, f) - x[static_cast<std::size_t>(f)], 2);
        expected += function.coefficients(k) * std::exp(-function.gamma * squared);
        magnitude += std::abs(function.coefficients(k));
      }
      EXPECT_NEAR(function(x.data()), expected, 1e-14 * magnitude) << features << " features, " << count << " vectors";
    }
  }
}

}  // namespace
}  // namespace thermodrift
