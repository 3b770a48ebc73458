// ColumnCache::cv_score, the searches' score from inner products kept per block, against
// least_squares_cv_score on the same columns (one Gram matrix over all rows): by time
// blocks and by runs, on the first call and on calls that find the products kept, and
// after the products were dropped.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/sim/law_family.hpp"
#include "thermodrift/tune/svr_tuning.hpp"
#include "tune/term_columns.hpp"

namespace thermodrift {
namespace {

void expect_same_score(ColumnCache& cache, const std::vector<std::string>& names, const std::vector<SampleRange>& blocks,
                       Eigen::Index grouped) {
  const LeastSquaresScore expected = least_squares_cv_score(cache.matrix(names), cache.target(), blocks, grouped);
  const LeastSquaresScore got = cache.cv_score(names, blocks, grouped);
  std::string set;
  for (const auto& name : names) set += name + " ";
  // Both solve the same normal equations, summed in another order: they agree to
  // rounding (1e-13-1e-10 here), except on a set that cannot predict its held-out blocks
  // (CV MSE far above the target's variance: the run's start held out with its on: term),
  // whose ill-conditioned solve amplifies rounding (7e-7 here).
  const Eigen::VectorXd& y = cache.target();
  const double variance = (y.array() - y.mean()).square().mean();
  const double tolerance = expected.cv_mse < 10 * variance ? 1e-9 : 1e-5;
  EXPECT_NEAR(got.cv_mse, expected.cv_mse, tolerance * expected.cv_mse) << set;
  EXPECT_NEAR(got.cancellation, expected.cancellation, tolerance * expected.cancellation) << set;
  // Each block's MSE, from the same held-out predictions; their geometric mean.
  const Eigen::VectorXd predicted = least_squares_cv_predictions(cache.matrix(names), y, blocks);
  ASSERT_EQ(got.block_mse.size(), blocks.size()) << set;
  double logs = 0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const SampleRange& block = blocks[b];
    const double mse = (y.segment(block.begin, block.size()) - predicted.segment(block.begin, block.size())).squaredNorm() /
                       static_cast<double>(block.size());
    EXPECT_NEAR(got.block_mse[b], mse, tolerance * mse) << set << "block " << b;
    logs += std::log(mse);
  }
  const double typical = std::exp(logs / static_cast<double>(blocks.size()));
  EXPECT_NEAR(got.typical_block_mse(), typical, tolerance * typical) << set;
  double mean = 0;
  for (const double mse : got.block_mse) mean += mse / static_cast<double>(blocks.size());
  EXPECT_LE(got.typical_block_mse(), mean * (1 + 1e-12)) << set << "(a geometric mean is at most the mean)";
}

TEST(ColumnCache, CvScoreFromKeptProductsMatchesTheGramOverAllRows) {
  const sim::UnitLaw unit = sim::draw_unit(7);
  const sim::ChamberRun run = sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 7, 2), 7);
  const ChamberLog log = sim::to_chamber_log(run);
  const std::size_t split = run.cycle_start_rows().at(1);
  const std::vector<std::vector<ChamberLog>> log_sets{{log}, {slice_rows(log, 0, split), slice_rows(log, split, log.rows())}};
  const std::vector<std::vector<std::string>> sets{
      {"rate"},
      {"lag:600", "hinge:600:-10", "hinge:600:10", "lagrate:600", "rate"},
      {"lag:600", "hinge:600:-10", "hinge:600:10", "lagrate:600", "rate", "dir:900:600", "gradrate:600:300"},
      {"lag:600", "hinge:600:-10", "hinge:600:10", "lagrate:600", "rate", "lag:150", "lag:600*lagrate:600"},
      {"lag2:900:300", "lag2rate:900:300", "rate", "play:1200:2", "on:600"},
  };
  for (const auto& logs : log_sets) {
    for (const FoldsBy by : {FoldsBy::time, FoldsBy::runs}) {
      if (by == FoldsBy::runs && logs.size() < 2) continue;
      SCOPED_TRACE(fmt::format("{} log(s), folds by {}", logs.size(), to_string(by)));
      ColumnCache cache(logs, 1, Pipeline{});
      const auto blocks = cache.blocks(10, by).blocks;
      for (int pass = 0; pass < 2; ++pass) {  // the second finds every product kept
        for (const auto& names : sets) expect_same_score(cache, names, blocks, names.size() > 3 ? 3 : 0);
      }
      // Other blocks: every product is computed again for them.
      const auto five = cache.blocks(5, FoldsBy::time).blocks;
      for (const auto& names : sets) expect_same_score(cache, names, five, 1);
    }
  }
}

// A sparse cache (the identification's) computes its columns on the decimated rows. Its
// exact_matrix is the every-row cache's columns bit for bit, terms with a short lag are
// computed on every row too, and the others and the scores of sets of them stay within a
// small part of their range of the exact ones.
TEST(ColumnCache, SparseColumnsStayCloseToTheExactOnes) {
  const sim::UnitLaw unit = sim::draw_unit(7);
  const ChamberLog log =
      sim::to_chamber_log(sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 7, 1), 7));
  Pipeline pipeline;
  pipeline.decimation = 10;
  ColumnCache exact({log}, 0, pipeline), sparse({log}, 0, pipeline, true);
  const std::vector<std::string> longer{"lag:600", "hinge:600:-10", "lagrate:600", "rate", "dir:900:600",
                                        "gradrate:600:300", "play:1200:2", "lag2:900:300", "lag:600*lagrate:600"};
  const std::vector<std::string> shorter{"lag:30", "lagrate:30", "dir:40:20", "gradrate:600:30"};
  std::vector<std::string> all = longer;
  all.insert(all.end(), shorter.begin(), shorter.end());
  const Eigen::MatrixXd expected = exact.matrix(all);
  EXPECT_TRUE((sparse.exact_matrix(all).array() == expected.array()).all());
  EXPECT_TRUE((sparse.matrix(shorter).array() == exact.matrix(shorter).array()).all());
  const Eigen::MatrixXd close = sparse.matrix(longer);
  double largest = 0;
  for (Eigen::Index j = 0; j < close.cols(); ++j) {
    const double range = expected.col(j).maxCoeff() - expected.col(j).minCoeff();
    const double error = (close.col(j) - expected.col(j)).cwiseAbs().maxCoeff();
    EXPECT_LT(error, 1e-3 * range) << all[static_cast<std::size_t>(j)];
    largest = std::max(largest, error / range);
  }
  EXPECT_GT(largest, 0) << "the sparse columns are computed apart";
  const auto blocks = exact.blocks(10, FoldsBy::time).blocks;
  const std::vector<std::string> node{"lag:600", "hinge:600:-10", "lagrate:600", "rate", "dir:900:600", "gradrate:600:300"};
  const double got = sparse.cv_score(node, blocks, 2).cv_mse, want = exact.cv_score(node, blocks, 2).cv_mse;
  EXPECT_NEAR(got, want, 1e-3 * want);
}

// A column that is zero outside one block (a hinge only the hottest block reaches): the
// fold that holds that block out knows nothing of it, and predicts the block exactly as
// the set without it does. (Before the normal equations were kept per block, a fold's
// were the whole minus the block, and rounding left a ratio of two rounding errors as
// the hinge's coefficient: on development law 6, 13,000 scored sets had held-out MSEs of
// 10^14-10^28.)
TEST(LeastSquaresCv, AColumnZeroOutsideTheHeldOutBlockDoesNotEnterItsFold) {
  const sim::UnitLaw unit = sim::draw_unit(6);
  const sim::ChamberRun run = sim::simulate_unit(unit, sim::draw_profile(sim::ProfileKind::cycle, unit, 6, 1), 6);
  ColumnCache cache({sim::to_chamber_log(run)}, 0, Pipeline{});
  const auto blocks = cache.blocks(10, FoldsBy::time).blocks;
  const Eigen::MatrixXd node = cache.matrix({"lag:600"});
  // The block that reaches highest, and a knot just above every other block's top.
  std::vector<double> top;
  for (const auto& block : blocks) top.push_back(node.col(0).segment(block.begin, block.size()).maxCoeff());
  const auto hottest = static_cast<std::size_t>(std::max_element(top.begin(), top.end()) - top.begin());
  double knot = -1e300;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    if (b != hottest) knot = std::max(knot, top[b]);
  }
  ASSERT_LT(knot + 0.5, top[hottest]) << "the hottest block must reach above the others";
  const std::vector<std::string> without{"lag:600", "hinge:600:-10", "hinge:600:10", "lagrate:600", "rate"};
  std::vector<std::string> with = without;
  with.push_back(fmt::format("hinge:600:{:.3f}", knot + 0.25));
  const Eigen::VectorXd predicted_with = least_squares_cv_predictions(cache.matrix(with), cache.target(), blocks);
  const Eigen::VectorXd predicted_without = least_squares_cv_predictions(cache.matrix(without), cache.target(), blocks);
  const SampleRange& block = blocks[hottest];
  const double scale = cache.target().cwiseAbs().maxCoeff();
  EXPECT_LT((predicted_with - predicted_without).segment(block.begin, block.size()).cwiseAbs().maxCoeff(), 1e-9 * scale);
  // The cached score agrees, and the other blocks do use the hinge.
  EXPECT_NEAR(cache.cv_score(with, blocks, 3).cv_mse, held_out_mse(predicted_with, cache.target(), blocks),
              1e-9 * held_out_mse(predicted_with, cache.target(), blocks));
  EXPECT_GT((predicted_with - predicted_without).cwiseAbs().maxCoeff(), 1e-9 * scale);
}

}  // namespace
}  // namespace thermodrift
