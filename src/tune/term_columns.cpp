#include "tune/term_columns.hpp"

#include <Eigen/Cholesky>

#include <limits>

#include <fmt/format.h>

#include "thermodrift/models/linear.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

ColumnCache::ColumnCache(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline) {
  // A term reading each other channel, so that every channel's smoothed value and rate is
  // recorded for the grad terms the searches offer.
  Pipeline recording = pipeline;
  recording.terms = {FeatureTerm(FeatureTerm::Kind::delta_t)};
  const std::size_t channels = logs.empty() ? 0 : logs.front().temperature.size();
  for (std::size_t c = 1; c < channels; ++c) recording.terms.push_back(FeatureTerm::parse(fmt::format("grad:{}-1", c + 1)));
  // The logs' kept rows end to end, each log a run (as feature_table joins them).
  std::vector<double> target;
  for (const auto& log : logs) {
    inputs_.push_back(record_inputs(recording, log, axis, temperature_channel_per_axis(log).at(axis), true));
    if (target.empty()) {
      run_start_ = {0};
    } else {
      run_start_.push_back(target.size());
    }
    target.insert(target.end(), inputs_.back().target.begin(), inputs_.back().target.end());
  }
  target_ = Eigen::Map<const Eigen::VectorXd>(target.data(), static_cast<Eigen::Index>(target.size()));
}

void ColumnCache::ensure(const std::vector<std::string>& names) {
  ++clock_;
  std::vector<FeatureTerm> missing;
  for (const auto& name : names) {
    const auto found = columns_.find(name);
    if (found == columns_.end()) {
      missing.push_back(FeatureTerm::parse(name));
    } else {
      found->second.last_use = clock_;
    }
  }
  if (missing.empty()) return;
  // Past the budget, the half of the columns used longest ago go: the terms a search keeps
  // in every set it scores stay, the time constants it has moved on from do not.
  const std::size_t column_bytes = static_cast<std::size_t>(target_.size()) * sizeof(double);
  if ((columns_.size() + missing.size()) * column_bytes > kBudgetBytes) {
    std::vector<std::uint64_t> uses;
    for (const auto& entry : columns_) uses.push_back(entry.second.last_use);
    const auto middle = uses.begin() + static_cast<std::ptrdiff_t>(uses.size() / 2);
    std::nth_element(uses.begin(), middle, uses.end());
    const std::uint64_t oldest_kept = *middle;
    std::erase_if(columns_, [&](const auto& entry) { return entry.second.last_use < oldest_kept; });
  }
  std::vector<Eigen::MatrixXd> parts;
  for (const auto& log : inputs_) parts.push_back(evaluate_terms(missing, log));
  for (std::size_t j = 0; j < missing.size(); ++j) {
    Column& entry = columns_[missing[j].name()];
    entry.last_use = clock_;
    Eigen::VectorXd& column = entry.values;
    column.resize(target_.size());
    Eigen::Index row = 0;
    for (const auto& part : parts) {
      column.segment(row, part.rows()) = part.col(static_cast<Eigen::Index>(j));
      row += part.rows();
    }
  }
}

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
