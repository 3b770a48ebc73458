// The partially linear SVR's kernel judged by nested CV after tuning (fit_model with an
// IdentifiedLinearPart): the linear part's figure is the blocked least-squares CV the
// searches compute, the kernel is left out where it only fits noise and kept where the
// residual has a shape every block repeats.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "thermodrift/tune/calibration.hpp"
#include "tune/term_columns.hpp"

namespace thermodrift {
namespace {

struct Data {
  Eigen::MatrixXd features;
  Eigen::VectorXd target;
};

// Two features over `count` rows: a slow ramp-like x1 and an x2 that sweeps [-1, 1] many
// times, so every block of a blocked CV holds its whole range. target = 2 x1 - x2 +
// `bend`·sin(4 x2) + white noise of std 0.1.
Data make_data(int count, double bend, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> noise(0.0, 0.1);
  Data data{Eigen::MatrixXd(count, 2), Eigen::VectorXd(count)};
  for (int i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) / count;
    const double x1 = std::sin(2 * M_PI * t) + t;
    const double x2 = std::sin(2 * M_PI * 37 * t + 0.3);
    data.features(i, 0) = x1;
    data.features(i, 1) = x2;
    data.target(i) = 2 * x1 - x2 + bend * std::sin(4 * x2) + noise(generator);
  }
  return data;
}

CalibrationOptions svr_options() {
  CalibrationOptions options;
  options.model = ModelKind::svr;
  options.partially_linear = true;
  SvrTuningOptions tuning;
  tuning.evaluations = 9;
  tuning.folds = 5;
  options.tuning = tuning;
  return options;
}

IdentifiedLinearPart blocks_of(const Data& data) {
  IdentifiedLinearPart identified;
  identified.held_out = cv_blocks(data.features.rows(), {0}, 10, FoldsBy::time);
  return identified;
}

// The partially linear SVR of fit_model on the two features, tuned by AFSA (9 evaluations).
FittedModel fit_svr(const Data& data, const IdentifiedLinearPart& identified) {
  return fit_model(data.features, data.target, {"a", "b"}, svr_options(), true, 0, &identified);
}

TEST(KernelCheck, ALinearDriftWithWhiteNoiseLeavesTheKernelOut) {
  const Data data = make_data(600, 0.0, 1);
  const IdentifiedLinearPart identified = blocks_of(data);
  const FittedModel fitted = fit_svr(data, identified);
  ASSERT_TRUE(fitted.fit.kernel_check.has_value());
  const KernelCheckRecord& check = *fitted.fit.kernel_check;
  EXPECT_FALSE(check.kept) << check.with_kernel_mse << " against " << check.linear_part_mse;
  EXPECT_EQ(check.folds, 10u);
  EXPECT_EQ(check.min_gain, svr_options().selection.min_gain);
  // The linear part's nested figure is the searches' blocked least-squares CV (which solves
  // normal equations with a ridge of 1e-9 of the diagonal; the check, QR).
  const double reference = least_squares_cv(data.features, data.target, identified.held_out.blocks);
  EXPECT_NEAR(check.linear_part_mse, reference, 1e-7 * reference);
  // Left out: no vectors, and the model predicts its linear part (plus the residual's mean).
  const auto& svr = std::get<SvrModel>(fitted.model);
  EXPECT_EQ(svr.function.support_vectors.rows(), 0);
  ASSERT_TRUE(fitted.fit.solver.has_value());
  EXPECT_EQ(fitted.fit.solver->termination, "not trained: kernel left out");
  ASSERT_TRUE(svr.linear_part.has_value());
  const Eigen::VectorXd linear = svr.linear_part->predict(data.features);
  for (Eigen::Index i = 0; i < data.features.rows(); i += 97) {
    const double row[2] = {data.features(i, 0), data.features(i, 1)};
    EXPECT_NEAR(svr.predict(std::span<const double>(row, 2)), linear(i) + svr.scaling.target_mean, 1e-9);
  }
  // The figure fit prints is the nested one, not the tuning's CV on the in-sample residual.
  const auto expected = expected_held_out(fitted.fit);
  ASSERT_TRUE(expected.has_value());
  EXPECT_EQ(expected->cv_mse, check.linear_part_mse);
  EXPECT_NE(expected->from.find("left out"), std::string::npos) << expected->from;
}

// keep_kernel (fit --keep-kernel): the same data as above, the kernel trained without the
// check, and the tuning's CV quoted as the expected held-out figure.
TEST(KernelCheck, KeepKernelTrainsTheKernelWithoutTheCheck) {
  const Data data = make_data(600, 0.0, 1);
  const IdentifiedLinearPart identified = blocks_of(data);
  CalibrationOptions options = svr_options();
  options.keep_kernel = true;
  const FittedModel fitted = fit_model(data.features, data.target, {"a", "b"}, options, true, 0, &identified);
  EXPECT_FALSE(fitted.fit.kernel_check.has_value());
  EXPECT_GT(std::get<SvrModel>(fitted.model).function.support_vectors.rows(), 0);
  ASSERT_TRUE(fitted.fit.solver.has_value());
  EXPECT_NE(fitted.fit.solver->termination, "not trained: kernel left out");
  const auto expected = expected_held_out(fitted.fit);
  ASSERT_TRUE(expected.has_value());
  ASSERT_TRUE(fitted.fit.tuning.has_value());
  EXPECT_EQ(expected->cv_mse, fitted.fit.tuning->objective_mse);
}

TEST(KernelCheck, AShapeEveryBlockRepeatsKeepsTheKernel) {
  const Data data = make_data(600, 0.8, 2);
  const IdentifiedLinearPart identified = blocks_of(data);
  const FittedModel fitted = fit_svr(data, identified);
  ASSERT_TRUE(fitted.fit.kernel_check.has_value());
  const KernelCheckRecord& check = *fitted.fit.kernel_check;
  EXPECT_TRUE(check.kept);
  // The bend's variance (0.32) is most of the linear part's held-out error; the noise's
  // (0.01) is what the kernel cannot remove.
  EXPECT_LT(check.with_kernel_mse, 0.2 * check.linear_part_mse);
  EXPECT_GT(check.with_kernel_mse, 0.005);
  EXPECT_GT(std::get<SvrModel>(fitted.model).function.support_vectors.rows(), 0);
  const auto expected = expected_held_out(fitted.fit);
  ASSERT_TRUE(expected.has_value());
  EXPECT_EQ(expected->cv_mse, check.with_kernel_mse);
}

// An identification's averaged linear part is refitted per fold as it was built: each
// set's least squares, averaged.
TEST(KernelCheck, AnAveragedLinearPartIsRefittedPerSetInEachFold) {
  const Data data = make_data(600, 0.0, 3);
  IdentifiedLinearPart identified = blocks_of(data);
  identified.averaged_sets = {{"a"}, {"a", "b"}};
  LinearModel average = fit_least_squares(data.features, data.target, linear_regressors(2));
  const LinearModel first = fit_least_squares(data.features.leftCols(1), data.target, linear_regressors(1));
  average.coefficients = (average.coefficients + Eigen::Vector2d(first.coefficients(0), 0)) / 2;
  average.intercept = (average.intercept + first.intercept) / 2;
  identified.fit = average;
  const FittedModel fitted = fit_svr(data, identified);
  ASSERT_TRUE(fitted.fit.kernel_check.has_value());
  const auto& blocks = identified.held_out.blocks;
  const Eigen::VectorXd held_out = (least_squares_cv_predictions(data.features.leftCols(1), data.target, blocks) +
                                    least_squares_cv_predictions(data.features, data.target, blocks)) /
                                   2;
  const double reference = held_out_mse(held_out, data.target, blocks);
  EXPECT_NEAR(fitted.fit.kernel_check->linear_part_mse, reference, 1e-7 * reference);
  EXPECT_GT(reference, least_squares_cv(data.features, data.target, blocks)) << "x2 matters: the sets differ";
}

}  // namespace
}  // namespace thermodrift
