// Reader of libsvm's sparse text format, one sample per line:
//   label index:value index:value ...
// with 1-based, strictly increasing indices. Missing indices are zeros; the dense
// result has as many columns as the largest index in the file.
#pragma once

#include <iosfwd>
#include <string>

#include <Eigen/Dense>

#include "thermodrift/stop_token.hpp"

namespace thermodrift {

// The data are held dense (drift models have a handful of features), so the reader bounds
// what a file may ask for: a larger index or a larger dense matrix is a DataError naming
// the line and column where the bound is crossed, never an allocation that exhausts memory.
inline constexpr long kMaxLibsvmFeatureIndex = 10'000;
inline constexpr long long kMaxLibsvmDenseCells = 1LL << 27;  // 1 GiB of doubles
// A line is read up to this many bytes, never held whole beyond it (10,000 features of
// 30 characters are 300 kB): a longer one is a DataError, as in a CSV log.
inline constexpr std::size_t kMaxLibsvmLineBytes = std::size_t{1} << 20;

struct LabelledData {
  Eigen::MatrixXd samples;  // one row per line of the file
  Eigen::VectorXd targets;  // the labels
};

// Throws DataError naming line and column (1-based) on a bad label, a bad or
// non-increasing index, a missing colon, a bad value, an index, dense size or line length
// above the bounds above, or a file without data lines.
// Blank lines are skipped. `stop` is asked every 4096 lines (Interrupted).
LabelledData read_libsvm(const std::string& path, const StopToken& stop = {});
// The same from a stream; `name` is the file name used in errors.
LabelledData read_libsvm(std::istream& input, const std::string& name, const StopToken& stop = {});

// Writes `data` in the same format (every column, full precision), as svm-train reads it.
void write_libsvm(std::ostream& output, const Eigen::MatrixXd& samples,
                  const Eigen::VectorXd& targets);

}  // namespace thermodrift
