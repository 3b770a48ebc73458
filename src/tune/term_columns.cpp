#include "tune/term_columns.hpp"

#include <Eigen/Cholesky>

#include <limits>

#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

// Pooled MSE of least squares (with an intercept) over held-out blocks: each block is
// predicted by the fit on the rest. Columns are scaled to a largest magnitude of 1 so that
// powers of large values keep the normal equations well scaled. One Gram matrix serves every
// fold (the fold's own rows subtracted), so a set costs two passes over the samples, not
// one QR per fold: the searches score thousands of sets. A ridge of 1e-9 of the diagonal
// settles nearly collinear columns (a hinge whose knot no sample passes is the node's
// level minus a constant); it moves the fits of well-determined columns by far less than
// the noise does.
Eigen::VectorXd least_squares_cv_predictions(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                             const std::vector<SampleRange>& blocks) {
  const Eigen::Index n = y.size();
  Eigen::MatrixXd design(n, x.cols() + 1);
  design.col(0).setOnes();
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    const double scale = x.col(j).cwiseAbs().maxCoeff();
    design.col(j + 1) = scale > 0 ? Eigen::VectorXd(x.col(j) / scale) : Eigen::VectorXd(x.col(j));
  }
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(design.cols(), design.cols());
  gram.selfadjointView<Eigen::Lower>().rankUpdate(design.transpose());
  gram = gram.selfadjointView<Eigen::Lower>();
  const Eigen::VectorXd moment = design.transpose() * y;
  Eigen::VectorXd predicted = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
  for (const SampleRange& block : blocks) {
    const auto rows = design.middleRows(block.begin, block.size());
    const auto target = y.segment(block.begin, block.size());
    Eigen::MatrixXd train = gram - rows.transpose() * rows;
    const Eigen::VectorXd rhs = moment - rows.transpose() * target;
    train.diagonal() += 1e-9 * train.diagonal().cwiseAbs() + Eigen::VectorXd::Constant(train.rows(), 1e-300);
    const Eigen::VectorXd beta = train.ldlt().solve(rhs);
    predicted.segment(block.begin, block.size()) = rows * beta;
  }
  return predicted;
}

double held_out_mse(const Eigen::VectorXd& predicted, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks) {
  double squared_error = 0;
  double held_out = 0;
  for (const SampleRange& block : blocks) {
    squared_error += (y.segment(block.begin, block.size()) - predicted.segment(block.begin, block.size())).squaredNorm();
    held_out += static_cast<double>(block.size());
  }
  return squared_error / held_out;
}

double least_squares_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks) {
  return held_out_mse(least_squares_cv_predictions(x, y, blocks), y, blocks);
}

}  // namespace thermodrift
