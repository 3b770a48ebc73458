// The reduced set (models/svr_reduce.hpp) against functions whose answer is known: one
// built from a few of the candidate points, and a trained SVR with most samples as
// support vectors.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <random>

#include "thermodrift/error.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/models/svr_reduce.hpp"

namespace thermodrift {
namespace {

// Two features along a slow trajectory, as a chamber cycle's terms are.
Eigen::MatrixXd trajectory(int count) {
  Eigen::MatrixXd samples(count, 2);
  for (int i = 0; i < count; ++i) {
    const double t = 6.0 * i / count;
    samples(i, 0) = std::sin(t);
    samples(i, 1) = std::cos(1.3 * t);
  }
  return samples;
}

// The first `vectors` points as support vectors, coefficients evenly from -1 to 1.
RbfDecisionFunction evenly_weighted(const Eigen::MatrixXd& points, int vectors, double bias = 0) {
  RbfDecisionFunction function;
  function.gamma = 1.0;
  function.support_vectors = points.topRows(vectors);
  function.coefficients = Eigen::VectorXd::LinSpaced(vectors, -1, 1);
  function.bias = bias;
  return function;
}

ReduceOptions keep(std::size_t vectors) {
  ReduceOptions options;
  options.max_vectors = vectors;
  return options;
}

// Whatever centres it picks, the coefficients and bias are the least-squares fit at them:
// the change is orthogonal to every kept kernel column and to the constant.
TEST(ReduceRbf, CoefficientsAreTheLeastSquaresFitAtTheChosenCentres) {
  const Eigen::MatrixXd points = trajectory(400);
  RbfDecisionFunction function;
  function.gamma = 3.0;
  function.support_vectors = points(Eigen::seq(0, 399, 5), Eigen::all);
  function.coefficients = Eigen::VectorXd::LinSpaced(80, -1, 1).array().sin().matrix();
  function.bias = 0.25;
  const ReducedSet reduced = reduce_rbf(function, points, keep(5));
  ASSERT_EQ(reduced.function.support_vectors.rows(), 5);
  const Eigen::VectorXd change = reduced.function.predict(points) - function.predict(points);
  EXPECT_GT(reduced.rms_change, 0);
  EXPECT_NEAR(change.sum(), 0, 1e-9 * points.rows());
  for (Eigen::Index c = 0; c < 5; ++c) {
    RbfDecisionFunction column;
    column.gamma = function.gamma;
    column.support_vectors = reduced.function.support_vectors.row(c);
    column.coefficients = Eigen::VectorXd::Ones(1);
    EXPECT_NEAR(column.predict(points).dot(change), 0, 1e-9 * points.rows()) << "centre " << c;
  }
}

TEST(ReduceRbf, ApproximatesATrainedSvrAndImprovesWithMoreVectors) {
  const Eigen::MatrixXd samples = trajectory(1200);
  std::mt19937 generator(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  Eigen::VectorXd targets(samples.rows());
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    targets(i) = std::tanh(2 * samples(i, 0)) + 0.5 * samples(i, 1) + noise(generator);
  }
  SvrOptions svr;
  svr.approximation = SvrApproximation::exact;  // SMO's many support vectors are what a reduced set is for
  svr.C = 100;
  svr.gamma = 1.0;
  svr.epsilon = 0.01;
  const SvrFit fit = SvrTrainer(svr).train(samples, targets);
  ASSERT_GT(fit.function.support_vectors.rows(), 500);  // the regime the reduction is for

  double previous = std::numeric_limits<double>::infinity();
  for (std::size_t vectors : {4, 8, 16, 32}) {
    ReduceOptions on_points = keep(vectors);
    on_points.refine_iterations = 0;
    const ReducedSet reduced = reduce_rbf(fit.function, samples, on_points);
    // Fewer when the rest of the kernel columns are within rounding of the chosen span.
    EXPECT_LE(static_cast<std::size_t>(reduced.function.support_vectors.rows()), vectors);
    EXPECT_EQ(reduced.original_vectors, static_cast<std::size_t>(fit.function.support_vectors.rows()));
    // Nested choices, each refitted by least squares: never worse with more vectors.
    EXPECT_LE(reduced.rms_change, previous * (1 + 1e-9)) << vectors << " vectors";
    previous = reduced.rms_change;
    // The figures describe the returned function.
    const Eigen::VectorXd change = reduced.function.predict(samples) - fit.function.predict(samples);
    EXPECT_NEAR(reduced.max_change, change.cwiseAbs().maxCoeff(), 1e-12);
    // Moving the centres off the points starts from these and keeps only steps that help.
    const ReducedSet refined = reduce_rbf(fit.function, samples, keep(vectors));
    EXPECT_LE(refined.rms_change, reduced.rms_change) << vectors << " vectors";
  }
  // 32 centres follow the fitted function within a fraction of the noise it was fitted through.
  EXPECT_LT(reduce_rbf(fit.function, samples, keep(32)).rms_change, 0.2 * 0.05);
}

TEST(ReduceRbf, KeepsASmallFunctionAndIsDeterministic) {
  const Eigen::MatrixXd points = trajectory(300);
  const RbfDecisionFunction small = evenly_weighted(points, 5, 0.1);
  const ReducedSet same = reduce_rbf(small, points, keep(5));
  EXPECT_EQ(same.function.support_vectors, small.support_vectors);
  EXPECT_EQ(same.function.coefficients, small.coefficients);
  EXPECT_EQ(same.rms_change, 0);

  const RbfDecisionFunction wide = evenly_weighted(points, 60, 0.1);
  const ReducedSet first = reduce_rbf(wide, points, keep(6));
  const ReducedSet second = reduce_rbf(wide, points, keep(6));
  EXPECT_EQ(first.function.support_vectors, second.function.support_vectors);
  EXPECT_EQ(first.function.coefficients, second.function.coefficients);
}

TEST(ReduceRbf, RefusesPointsOfAnotherWidthAndNoVectors) {
  RbfDecisionFunction function;
  function.gamma = 1.0;
  function.support_vectors = trajectory(10);
  function.coefficients = Eigen::VectorXd::Ones(10);
  EXPECT_THROW(reduce_rbf(function, Eigen::MatrixXd::Zero(20, 3), keep(4)), UsageError);
  EXPECT_THROW(reduce_rbf(function, trajectory(20), keep(0)), UsageError);
}

// A stop asked for (Ctrl-C in `compress`) ends the reduction with Interrupted, at once.
TEST(ReduceRbf, StopsWhenAStopIsRequested) {
  const Eigen::MatrixXd points = trajectory(300);
  const RbfDecisionFunction function = evenly_weighted(points, 60);
  std::atomic<bool> stop{true};
  ReduceOptions options = keep(6);
  options.stop = StopToken(stop);
  EXPECT_THROW(reduce_rbf(function, points, options), Interrupted);
  stop = false;
  EXPECT_EQ(reduce_rbf(function, points, options).function.support_vectors.rows(), 6);
}

}  // namespace
}  // namespace thermodrift
