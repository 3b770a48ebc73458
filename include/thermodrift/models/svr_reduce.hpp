// A smaller RBF decision function that predicts like a larger one: the reduced set a
// navigation computer can afford (docs/svr.md, "Compressed models").
//
// Drift data with a small ε make most training samples support vectors (2008 of 2091 on
// a one-cycle log); each costs an exp per sample in the field. The reduced set keeps K of
// centres, chosen among the evaluation points by kernel matching pursuit (orthogonal
// matching pursuit over the kernel columns, Vincent & Bengio 2002) and then moved off them
// by gradient descent (pre-images), with the coefficients and bias fitted to the original
// function by least squares at the evaluation points (the training samples, or the support
// vectors when only the model is at hand). The result is an ordinary decision
// function with the same γ: the model file, the compensator and the C header take it
// unchanged.
//
//   ReduceOptions options;
//   options.max_vectors = 32;
//   ReducedSet reduced = reduce_rbf(svr.function, scaled_training_samples, options);
//   svr.function = reduced.function;  // reduced.rms_change: what it costs on those points
#pragma once

#include <cstddef>
#include <string>

#include <Eigen/Dense>

#include "thermodrift/models/svr.hpp"

namespace thermodrift {

struct ReduceOptions {
  std::size_t max_vectors = 32;     // K: centres in the result
  // Evaluation points and candidate centres are evenly strided subsets of the points
  // given when there are more (the kernel matrix is points x candidates doubles).
  std::size_t max_points = 4000;
  std::size_t max_candidates = 1500;
  // Gradient steps that then move the chosen centres off the sample points (pre-images),
  // the coefficients refitted at each; 0 keeps the centres on sample points.
  std::size_t refine_iterations = 300;
  StopToken stop;  // asked at each centre chosen and each refinement step: throws Interrupted

  bool IsValid(std::string* error) const;
};

struct ReducedSet {
  RbfDecisionFunction function;
  std::size_t original_vectors = 0;
  std::size_t points = 0;   // evaluation points the fit and the figures below used
  double rms_change = 0;    // RMS of reduced − original over those points (the function's units)
  double max_change = 0;    // largest |reduced − original| there
};

// `points` holds one sample per row in the function's (standardized) feature units. A
// function with at most K vectors is returned as it is. Deterministic.
ReducedSet reduce_rbf(const RbfDecisionFunction& function, const Eigen::MatrixXd& points,
                      const ReduceOptions& options);

}  // namespace thermodrift
