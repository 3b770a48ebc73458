#include "tune/term_columns.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "thermodrift/error.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/tune/svr_tuning.hpp"

namespace thermodrift {

ColumnCache::ColumnCache(const std::vector<ChamberLog>& logs, std::size_t axis, const Pipeline& pipeline, bool sparse) {
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
    if (sparse && pipeline.decimation > 1) {
      sparse_.push_back(sparse_inputs(inputs_.back(), pipeline.decimation));
      sparse_shortest_ = std::max(sparse_shortest_, kSparseSteps * static_cast<double>(pipeline.decimation) *
                                                        sparse_.back().dense_step_seconds);
    }
  }
  target_ = Eigen::Map<const Eigen::VectorXd>(target.data(), static_cast<Eigen::Index>(target.size()));
}

namespace {

// The columns of `terms` over each log's inputs, end to end.
Eigen::MatrixXd joined_columns(const std::vector<FeatureTerm>& terms, const std::vector<RecordedInputs>& logs,
                               Eigen::Index rows) {
  Eigen::MatrixXd joined(rows, static_cast<Eigen::Index>(terms.size()));
  if (terms.empty()) return joined;
  Eigen::Index row = 0;
  for (const auto& log : logs) {
    const Eigen::MatrixXd part = evaluate_terms(terms, log);
    joined.middleRows(row, part.rows()) = part;
    row += part.rows();
  }
  return joined;
}

}  // namespace

Eigen::MatrixXd ColumnCache::exact_matrix(const std::vector<std::string>& names) {
  if (sparse_.empty()) return matrix(names);
  std::vector<FeatureTerm> terms;
  for (const auto& name : names) terms.push_back(FeatureTerm::parse(name));
  return joined_columns(terms, inputs_, target_.size());
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
    // Their inner products go too (ids are never reused, so none can be found again).
    drop_products();
  }
  // The terms a sparse cache computes on every row: those with a short time constant.
  std::vector<FeatureTerm> dense, sparse;
  for (auto& term : missing) {
    const auto constants = term.time_constants();
    const bool short_lag = std::any_of(constants.begin(), constants.end(), [&](double tau) { return tau < sparse_shortest_; });
    (sparse_.empty() || short_lag ? dense : sparse).push_back(std::move(term));
  }
  // Each batch evaluated over its inputs, its columns kept under their names.
  const auto keep = [&](const std::vector<FeatureTerm>& terms, const std::vector<RecordedInputs>& over) {
    const Eigen::MatrixXd joined = joined_columns(terms, over, target_.size());
    for (std::size_t j = 0; j < terms.size(); ++j) {
      Column& entry = columns_[terms[j].name()];
      entry.last_use = clock_;
      entry.id = next_id_++;
      entry.values = joined.col(static_cast<Eigen::Index>(j));
      const double largest = entry.values.size() > 0 ? entry.values.cwiseAbs().maxCoeff() : 0.0;
      entry.scale = largest > 0 ? largest : 1.0;
    }
  };
  keep(dense, inputs_);
  keep(sparse, sparse_);
}

namespace {

// The least-squares coefficients from normal equations, with a ridge of 1e-9 of the
// diagonal (below).
Eigen::VectorXd solve_normal(Eigen::MatrixXd normal, const Eigen::VectorXd& rhs) {
  normal.diagonal() += 1e-9 * normal.diagonal().cwiseAbs() + Eigen::VectorXd::Constant(normal.rows(), 1e-300);
  return normal.ldlt().solve(rhs);
}

// The normal equations of least squares with an intercept on [1, x], the columns of x
// scaled to a largest magnitude of 1 so that powers of large values keep them well
// scaled, per segment of the held-out blocks.
struct NormalEquations {
  Eigen::MatrixXd design;  // n x (1 + columns)
  Segments segments;
  SegmentedNormalEquations equations;

  NormalEquations(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks)
      : design(y.size(), x.cols() + 1), segments(segments_of(blocks, y.size())) {
    design.col(0).setOnes();
    for (Eigen::Index j = 0; j < x.cols(); ++j) {
      const double scale = x.col(j).cwiseAbs().maxCoeff();
      design.col(j + 1) = scale > 0 ? Eigen::VectorXd(x.col(j) / scale) : Eigen::VectorXd(x.col(j));
    }
    const Eigen::Index q = design.cols();
    equations.gram.assign(segments.count, Eigen::MatrixXd::Zero(q, q));
    equations.moment.assign(segments.count, Eigen::VectorXd::Zero(q));
    for (const Segments::Range& range : segments.ranges) {
      const auto rows = design.middleRows(range.begin, range.end - range.begin);
      Eigen::MatrixXd& gram = equations.gram[range.segment];
      gram.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
      equations.moment[range.segment] += rows.transpose() * y.segment(range.begin, range.end - range.begin);
    }
    for (auto& gram : equations.gram) gram = Eigen::MatrixXd(gram.selfadjointView<Eigen::Lower>());
  }

  // Each block's rows predicted by the fit on the rest (NaN on rows no block holds out).
  Eigen::VectorXd held_out_predictions() const {
    Eigen::VectorXd predicted = Eigen::VectorXd::Constant(design.rows(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t b = 0; b < segments.blocks.size(); ++b) {
      const SampleRange& block = segments.blocks[b];
      predicted.segment(block.begin, block.size()) =
          design.middleRows(block.begin, block.size()) * equations.fold_coefficients(b);
    }
    return predicted;
  }
};

}  // namespace

Segments segments_of(const std::vector<SampleRange>& blocks, Eigen::Index rows) {
  Segments segments;
  segments.blocks = blocks;
  segments.count = blocks.size() + 1;
  std::vector<std::size_t> order(blocks.size());
  for (std::size_t b = 0; b < order.size(); ++b) order[b] = b;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return blocks[a].begin < blocks[b].begin; });
  Eigen::Index at = 0;
  for (const std::size_t b : order) {
    const SampleRange& block = blocks[b];
    if (block.begin < at || block.end > rows || block.end < block.begin) {
      throw Error("cross-validation blocks overlap or leave the samples");
    }
    if (block.begin > at) segments.ranges.push_back({blocks.size(), at, block.begin});
    if (block.end > block.begin) segments.ranges.push_back({b, block.begin, block.end});
    at = block.end;
  }
  if (at < rows) segments.ranges.push_back({blocks.size(), at, rows});
  return segments;
}

// A ridge of 1e-9 of the diagonal settles nearly collinear columns (a hinge whose knot no
// sample passes is the node's level minus a constant); it moves the fits of
// well-determined columns by far less than the noise does.
Eigen::VectorXd SegmentedNormalEquations::coefficients() const { return fold_coefficients(gram.size()); }

Eigen::VectorXd SegmentedNormalEquations::fold_coefficients(std::size_t block) const {
  return solve_normal(gram_without(block), moment_without(block));
}

Eigen::MatrixXd SegmentedNormalEquations::gram_without(std::size_t block) const {
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(gram.front().rows(), gram.front().cols());
  for (std::size_t s = 0; s < gram.size(); ++s) {
    if (s != block) sum += gram[s];
  }
  return sum;
}

Eigen::VectorXd SegmentedNormalEquations::moment_without(std::size_t block) const {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(moment.front().size());
  for (std::size_t s = 0; s < moment.size(); ++s) {
    if (s != block) sum += moment[s];
  }
  return sum;
}

// The normal equations per segment serve every fold, so a set costs two passes over the
// samples, not one QR per fold: the searches score thousands of sets.
Eigen::VectorXd least_squares_cv_predictions(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                             const std::vector<SampleRange>& blocks) {
  return NormalEquations(x, y, blocks).held_out_predictions();
}

LeastSquaresScore least_squares_cv_score(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                         const std::vector<SampleRange>& blocks, Eigen::Index grouped) {
  const NormalEquations equations(x, y, blocks);
  const Eigen::VectorXd beta = equations.equations.coefficients();
  return {held_out_mse(equations.held_out_predictions(), y, blocks),
          cancellation(equations.design.rightCols(x.cols()), beta.tail(x.cols()), grouped), {}};
}

void ColumnCache::set_blocks(const std::vector<SampleRange>& blocks) {
  segments_ = segments_of(blocks, target_.size());
  ones_ = Eigen::VectorXd::Ones(target_.size());
  drop_products();
}

void ColumnCache::drop_products() {
  products_.clear();
  with_target_.clear();
  pool_.clear();
}

std::size_t ColumnCache::segment_products(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const std::size_t offset = pool_.size();
  pool_.resize(offset + segments_.count, 0.0);
  for (const Segments::Range& range : segments_.ranges) {
    const Eigen::Index length = range.end - range.begin;
    pool_[offset + range.segment] += a.segment(range.begin, length).dot(b.segment(range.begin, length));
  }
  return offset;
}

LeastSquaresScore ColumnCache::cv_score(const std::vector<std::string>& names, const std::vector<SampleRange>& blocks,
                                        Eigen::Index grouped) {
  const auto same = [](const SampleRange& a, const SampleRange& b) { return a.begin == b.begin && a.end == b.end; };
  if (segments_.count == 0 ||
      !std::equal(blocks.begin(), blocks.end(), segments_.blocks.begin(), segments_.blocks.end(), same)) {
    set_blocks(blocks);
  }
  ensure(names);
  // Past the budget the products go; the names' columns stay (ensure just kept them).
  constexpr std::size_t kPoolBudget = std::size_t{64} << 20;
  if (pool_.size() * sizeof(double) > kPoolBudget) drop_products();
  const auto q = static_cast<Eigen::Index>(names.size() + 1);
  std::vector<const Eigen::VectorXd*> values(names.size() + 1, &ones_);
  std::vector<std::uint64_t> ids(names.size() + 1, 0);
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(q);
  for (std::size_t j = 0; j < names.size(); ++j) {
    const Column& column = columns_.at(names[j]);
    values[j + 1] = &column.values;
    ids[j + 1] = column.id;
    scale(static_cast<Eigen::Index>(j + 1)) = 1.0 / column.scale;
  }
  // Per segment, the Gram matrix and moment of [1, x] with x's columns scaled to a largest
  // magnitude of 1 (as NormalEquations scales them).
  const std::size_t count = segments_.count;
  SegmentedNormalEquations equations;
  equations.gram.assign(count, Eigen::MatrixXd(q, q));
  equations.moment.assign(count, Eigen::VectorXd(q));
  for (Eigen::Index a = 0; a < q; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    for (Eigen::Index b = a; b < q; ++b) {
      const auto ub = static_cast<std::size_t>(b);
      const std::uint64_t low = std::min(ids[ua], ids[ub]), high = std::max(ids[ua], ids[ub]);
      const std::uint64_t key = (low << 32) | high;
      auto found = products_.find(key);
      if (found == products_.end()) found = products_.emplace(key, segment_products(*values[ua], *values[ub])).first;
      for (std::size_t s = 0; s < count; ++s) {
        equations.gram[s](a, b) = equations.gram[s](b, a) = pool_[found->second + s] * scale(a) * scale(b);
      }
    }
    auto found = with_target_.find(ids[ua]);
    if (found == with_target_.end()) found = with_target_.emplace(ids[ua], segment_products(*values[ua], target_)).first;
    for (std::size_t s = 0; s < count; ++s) equations.moment[s](a) = pool_[found->second + s] * scale(a);
  }
  // Each block predicted by the fit on the rest; its residuals from the columns (not from
  // the inner products, which would lose digits where a fit's terms cancel).
  double squared_error = 0, held_out = 0;
  Eigen::VectorXd residual;
  LeastSquaresScore score;
  score.block_mse.reserve(blocks.size());
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const Eigen::VectorXd beta = equations.fold_coefficients(b);
    const SampleRange& block = blocks[b];
    residual = target_.segment(block.begin, block.size());
    for (Eigen::Index j = 0; j < q; ++j) {
      residual -= (beta(j) * scale(j)) * values[static_cast<std::size_t>(j)]->segment(block.begin, block.size());
    }
    const double block_error = residual.squaredNorm();
    score.block_mse.push_back(block.size() > 0 ? block_error / static_cast<double>(block.size()) : 0.0);
    squared_error += block_error;
    held_out += static_cast<double>(block.size());
  }
  score.cv_mse = held_out > 0 ? squared_error / held_out : 0.0;
  // The cancellation of the fit on all rows (models/linear.hpp's, from the same sums):
  // the spread of v = Σ_J x_j β_j is √(Σv²/n − (Σv/n)²), Σv = Σ_J β_j Σx_j.
  const Eigen::MatrixXd total_gram = equations.gram_without(count);
  const Eigen::VectorXd beta = solve_normal(total_gram, equations.moment_without(count));
  const double n = total_gram(0, 0);
  if (n < 2) return score;
  const auto spread = [&](Eigen::Index first, Eigen::Index count) {
    const auto b = beta.segment(first, count);
    const double sum = total_gram.row(0).segment(first, count).dot(b);
    const double squares = b.dot(total_gram.block(first, first, count, count) * b);
    return std::sqrt(std::max(0.0, squares / n - (sum / n) * (sum / n)));
  };
  const Eigen::Index p = q - 1;
  const double whole = spread(1, p);
  if (!(whole > 0)) return score;
  double parts = grouped > 0 ? spread(1, grouped) : 0.0;
  for (Eigen::Index j = grouped; j < p; ++j) parts += spread(1 + j, 1);
  score.cancellation = parts / whole;
  return score;
}

double LeastSquaresScore::typical_block_mse() const {
  if (block_mse.empty()) return cv_mse;
  double logs = 0;
  for (const double mse : block_mse) logs += std::log(std::max(mse, std::numeric_limits<double>::min()));
  return std::exp(logs / static_cast<double>(block_mse.size()));
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

LinearModel averaged_least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                   const std::vector<std::string>& names,
                                   const std::vector<std::vector<std::string>>& sets) {
  LinearModel average;
  average.regressors = linear_regressors(names.size());
  average.coefficients = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  const double weight = 1.0 / static_cast<double>(sets.size());
  for (const auto& set : sets) {
    std::vector<Eigen::Index> columns;
    for (const auto& name : set) {
      const auto at = std::find(names.begin(), names.end(), name);
      if (at == names.end()) throw Error(fmt::format("an averaged set names {}, not one of the terms", name));
      columns.push_back(at - names.begin());
    }
    const LinearModel fit = fit_least_squares(x(Eigen::all, columns), y, linear_regressors(columns.size()));
    for (std::size_t j = 0; j < columns.size(); ++j) {
      average.coefficients[columns[j]] += weight * fit.coefficients[static_cast<Eigen::Index>(j)];
    }
    average.intercept += weight * fit.intercept;
  }
  return average;
}

double least_squares_cv(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const std::vector<SampleRange>& blocks) {
  return held_out_mse(least_squares_cv_predictions(x, y, blocks), y, blocks);
}

}  // namespace thermodrift
