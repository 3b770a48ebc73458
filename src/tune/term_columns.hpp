// What the feature searches share: the columns of candidate terms over the training logs,
// computed once per term, and the blocked cross-validation of a least-squares fit on them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Dense>

#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/tune/calibration.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

// The score of a set no fit could be judged for (and the start of every minimum).
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The blocked CV MSE of a least-squares fit and the cancellation of the fit on all rows
// (models/linear.hpp), as least_squares_cv_score and ColumnCache::cv_score give them.
struct LeastSquaresScore {
  double cv_mse = 0;
  double cancellation = 1;
  std::vector<double> block_mse;  // ColumnCache::cv_score: each held-out block's MSE, in order
  // The geometric mean of block_mse (FeatureSelectionOptions::CvScore::geometric).
  double typical_block_mse() const;
};

// The samples cut by held-out blocks into segments: each block (segment = its index),
// then the rows no block holds (segment = blocks.size()); `ranges` lists them in row order.
struct Segments {
  std::vector<SampleRange> blocks;
  struct Range {
    std::size_t segment;
    Eigen::Index begin, end;
  };
  std::vector<Range> ranges;
  std::size_t count = 0;  // blocks.size() + 1
};
// Error when blocks overlap or leave [0, rows).
Segments segments_of(const std::vector<SampleRange>& blocks, Eigen::Index rows);

// The normal equations of least squares with an intercept, kept per segment, so that a
// fold's (every segment but its block's) is a sum, never the whole minus the block: a
// column that is zero outside one block (a hinge only the hottest block reaches) is then
// exactly zero in that fold's equations, and the ridge of 1e-9 of the diagonal sets its
// coefficient to 0. As a difference, rounding left ±1e-17 there, and the coefficient was
// a ratio of two rounding errors: held-out MSEs of 10^14-10^28 for such sets.
struct SegmentedNormalEquations {
  std::vector<Eigen::MatrixXd> gram;    // per segment, (1 + columns)²
  std::vector<Eigen::VectorXd> moment;  // per segment, Σ [1, x]·y
  Eigen::VectorXd coefficients() const;                        // on every segment
  Eigen::VectorXd fold_coefficients(std::size_t block) const;  // on every segment but `block`
  // The sums over every segment but `block` (a block past the last: every segment).
  Eigen::MatrixXd gram_without(std::size_t block) const;
  Eigen::VectorXd moment_without(std::size_t block) const;
};

// The ready, decimated samples of every term asked for so far, one column per term name:
// each new batch of terms is one pass of the terms over the logs' recorded inputs. The time-constant search
// asks for many columns, so past a byte budget the half used longest ago is dropped.
//
// `sparse`: the columns are computed on the decimated rows alone (sparse_inputs, the filters
// fed a straight line between them), about `decimation` times less work than every row; they
// differ from the model's own columns by how far the 100 s means bend between decimated rows.
// Terms with a time constant under kSparseSteps of those rows' steps are computed on every
// row: a lag that short follows the bends. For a search that scores thousands of sets;
// `exact_matrix` gives the model's columns.
class ColumnCache {
 public:
  ColumnCache(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline, bool sparse = false);

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
  // The named columns computed on every row, as the model computes them (not kept): for a
  // sparse cache, what its result is fitted and judged on.
  Eigen::MatrixXd exact_matrix(const std::vector<std::string>& names);

  // least_squares_cv_score of the named columns over `blocks`, from their inner products
  // per block: each pair of columns is multiplied once and kept, so a set that adds one
  // term to a scored set costs one pass per new pair, not a Gram matrix over all samples.
  // Blocks other than the last call's start the kept products anew.
  LeastSquaresScore cv_score(const std::vector<std::string>& names, const std::vector<SampleRange>& blocks,
                             Eigen::Index grouped);

 private:
  static constexpr std::size_t kBudgetBytes = std::size_t{128} << 20;
  static constexpr double kSparseSteps = 5;
  double sparse_shortest_ = 0;  // seconds: the shortest time constant computed on sparse rows
  // The terms' inputs over each log, smoothed once (every temperature channel recorded).
  std::vector<RecordedInputs> inputs_;
  std::vector<RecordedInputs> sparse_;  // sparse_inputs of each, for a sparse cache
  Eigen::VectorXd target_;
  std::vector<std::size_t> run_start_;
  struct Column {
    Eigen::VectorXd values;
    std::uint64_t last_use = 0;  // the clock_ of the last ensure that asked for it
    std::uint64_t id = 0;        // never reused: the key of its inner products
    double scale = 1;            // its largest magnitude (1 when all zero)
  };
  std::map<std::string, Column> columns_;
  std::uint64_t clock_ = 0;
  std::uint64_t next_id_ = 1;  // 0: the constant column (the intercept)

  // cv_score's inner products, per segment of the blocks it was last asked for.
  Segments segments_;
  Eigen::VectorXd ones_;  // the intercept's column, id 0
  // Per segment, at an offset into pool_: Σ a·b for the columns of ids a ≤ b (key
  // a·2^32 + b), and Σ a·y (key a). Dropped whole past a byte budget.
  std::unordered_map<std::uint64_t, std::size_t> products_, with_target_;
  std::vector<double> pool_;
  void set_blocks(const std::vector<SampleRange>& blocks);
  void drop_products();  // every kept inner product (pool_ and its keys)
  // Σ a·b over each segment, into pool_; returns its offset.
  std::size_t segment_products(const Eigen::VectorXd& a, const Eigen::VectorXd& b);
};

// The least-squares fits of several term sets (each a subset of `names`, the columns of
// x) averaged with equal weights: an identification's averaged linear part, over `names`.
LinearModel averaged_least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                   const std::vector<std::string>& names,
                                   const std::vector<std::vector<std::string>>& sets);

// Pooled MSE of least squares (with an intercept) over held-out `blocks` (contiguous
// blocks in time, or runs): each block is predicted by the fit on the rest.
double least_squares_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks);
// The blocked CV MSE of least squares on x and the cancellation of the fit on all rows
// (models/linear.hpp: the first `grouped` columns one part), from one Gram matrix.
LeastSquaresScore least_squares_cv_score(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                         const std::vector<SampleRange>& blocks, Eigen::Index grouped);
// The held-out predictions behind it: each block's rows by the fit on the rest (NaN on
// rows no block holds out), and their pooled MSE.
Eigen::VectorXd least_squares_cv_predictions(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                             const std::vector<SampleRange>& blocks);
double held_out_mse(const Eigen::VectorXd& predicted, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks);

}  // namespace thermodrift
