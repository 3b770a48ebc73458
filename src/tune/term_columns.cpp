#include "tune/term_columns.hpp"

#include <Eigen/Cholesky>

#include <limits>

#include "thermodrift/models/linear.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

namespace {

// The normal equations of least squares with an intercept on [1, x], the columns of x
// scaled to a largest magnitude of 1 so that powers of large values keep them well scaled.
struct NormalEquations {
  Eigen::MatrixXd design;  // n x (1 + columns)
  Eigen::MatrixXd gram;
  Eigen::VectorXd moment;

  NormalEquations(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) : design(y.size(), x.cols() + 1) {
    design.col(0).setOnes();
    for (Eigen::Index j = 0; j < x.cols(); ++j) {
      const double scale = x.col(j).cwiseAbs().maxCoeff();
      design.col(j + 1) = scale > 0 ? Eigen::VectorXd(x.col(j) / scale) : Eigen::VectorXd(x.col(j));
    }
    gram = Eigen::MatrixXd::Zero(design.cols(), design.cols());
    gram.selfadjointView<Eigen::Lower>().rankUpdate(design.transpose());
    gram = gram.selfadjointView<Eigen::Lower>();
    moment = design.transpose() * y;
  }

  static Eigen::VectorXd solve(Eigen::MatrixXd normal, const Eigen::VectorXd& rhs) {
    normal.diagonal() += 1e-9 * normal.diagonal().cwiseAbs() + Eigen::VectorXd::Constant(normal.rows(), 1e-300);
    return normal.ldlt().solve(rhs);
  }

  // Each block's rows predicted by the fit on the rest (NaN on rows no block holds out).
  Eigen::VectorXd held_out_predictions(const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks) const {
    Eigen::VectorXd predicted = Eigen::VectorXd::Constant(y.size(), std::numeric_limits<double>::quiet_NaN());
    for (const SampleRange& block : blocks) {
      const auto rows = design.middleRows(block.begin, block.size());
      const Eigen::VectorXd beta =
          solve(gram - rows.transpose() * rows, moment - rows.transpose() * y.segment(block.begin, block.size()));
      predicted.segment(block.begin, block.size()) = rows * beta;
    }
    return predicted;
  }
};

}  // namespace

// One Gram matrix serves every fold (the fold's own rows subtracted), so a set costs two
// passes over the samples, not one QR per fold: the searches score thousands of sets. A
// ridge of 1e-9 of the diagonal settles nearly collinear columns (a hinge whose knot no
// sample passes is the node's level minus a constant); it moves the fits of
// well-determined columns by far less than the noise does.
Eigen::VectorXd least_squares_cv_predictions(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                             const std::vector<SampleRange>& blocks) {
  return NormalEquations(x, y).held_out_predictions(y, blocks);
}

LeastSquaresScore least_squares_cv_score(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                         const std::vector<SampleRange>& blocks, Eigen::Index grouped) {
  const NormalEquations equations(x, y);
  const Eigen::VectorXd beta = NormalEquations::solve(equations.gram, equations.moment);
  return {held_out_mse(equations.held_out_predictions(y, blocks), y, blocks),
          cancellation(equations.design.rightCols(x.cols()), beta.tail(x.cols()), grouped)};
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
