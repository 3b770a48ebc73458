#include "tune/term_columns.hpp"

#include <Eigen/QR>

#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

// Pooled MSE of least squares (with an intercept) over blocked folds: each block is
// predicted by the fit on the rest. Columns are scaled first so that powers of large
// values do not spoil the QR's rank decisions.
double least_squares_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, int folds) {
  const Eigen::Index n = y.size();
  Eigen::MatrixXd design(n, x.cols() + 1);
  design.col(0).setOnes();
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    const double scale = x.col(j).cwiseAbs().maxCoeff();
    design.col(j + 1) = scale > 0 ? Eigen::VectorXd(x.col(j) / scale) : Eigen::VectorXd(x.col(j));
  }
  double squared_error = 0;
  for (const SampleRange& block : blocked_folds(n, folds)) {
    const Eigen::Index train_rows = n - block.size();
    Eigen::MatrixXd a(train_rows, design.cols());
    Eigen::VectorXd b(train_rows);
    a.topRows(block.begin) = design.topRows(block.begin);
    a.bottomRows(n - block.end) = design.bottomRows(n - block.end);
    b.head(block.begin) = y.head(block.begin);
    b.tail(n - block.end) = y.tail(n - block.end);
    const Eigen::VectorXd beta = a.colPivHouseholderQr().solve(b);
    const Eigen::VectorXd residual = y.segment(block.begin, block.size()) -
                                     design.middleRows(block.begin, block.size()) * beta;
    squared_error += residual.squaredNorm();
  }
  return squared_error / static_cast<double>(n);
}

}  // namespace thermodrift
