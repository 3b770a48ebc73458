// What the feature searches share: the columns of candidate terms over the training logs,
// computed once per term, and the blocked cross-validation of a least-squares fit on them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/tune/calibration.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

// The ready, decimated samples of every term asked for so far, one column per term name:
// each new batch of terms is one pass of the terms over the logs' recorded inputs. The time-constant search
// asks for many columns, so past a byte budget the half used longest ago is dropped.
class ColumnCache {
 public:
  ColumnCache(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline);

  const Eigen::VectorXd& target() const { return target_; }
  // The held-out blocks of the searches' cross-validation (cv_blocks).
  HeldOutBlocks blocks(int folds, FoldsBy by) const {
    return cv_blocks(target_.size(), run_start_, folds, by);
  }

  void ensure(const std::vector<std::string>& names);

  Eigen::MatrixXd matrix(const std::vector<std::string>& names) {
    ensure(names);
    Eigen::MatrixXd x(target_.size(), static_cast<Eigen::Index>(names.size()));
    for (std::size_t j = 0; j < names.size(); ++j) x.col(static_cast<Eigen::Index>(j)) = columns_.at(names[j]).values;
    return x;
  }

 private:
  static constexpr std::size_t kBudgetBytes = std::size_t{128} << 20;
  // The terms' inputs over each log, smoothed once (every temperature channel recorded).
  std::vector<RecordedInputs> inputs_;
  Eigen::VectorXd target_;
  std::vector<std::size_t> run_start_;
  struct Column {
    Eigen::VectorXd values;
    std::uint64_t last_use = 0;  // the clock_ of the last ensure that asked for it
  };
  std::map<std::string, Column> columns_;
  std::uint64_t clock_ = 0;
};

// Pooled MSE of least squares (with an intercept) over held-out `blocks` (contiguous
// blocks in time, or runs): each block is predicted by the fit on the rest.
double least_squares_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks);
// The blocked CV MSE of least squares on x and the cancellation of the fit on all rows
// (models/linear.hpp: the first `grouped` columns one part), from one Gram matrix.
struct LeastSquaresScore {
  double cv_mse = 0;
  double cancellation = 1;
};
LeastSquaresScore least_squares_cv_score(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                         const std::vector<SampleRange>& blocks, Eigen::Index grouped);
// The held-out predictions behind it: each block's rows by the fit on the rest (NaN on
// rows no block holds out), and their pooled MSE.
Eigen::VectorXd least_squares_cv_predictions(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                             const std::vector<SampleRange>& blocks);
double held_out_mse(const Eigen::VectorXd& predicted, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks);

}  // namespace thermodrift
