#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <fmt/format.h>

#include "thermodrift/error.hpp"
#include "thermodrift/io/libsvm_reader.hpp"

namespace thermodrift {
namespace {

LabelledData read_text(const std::string& text) {
  std::istringstream input(text);
  return read_libsvm(input, "data.libsvm");
}

// The DataError thrown for `text`, which must throw one.
DataError error_of(const std::string& text) {
  try {
    read_text(text);
  } catch (const DataError& error) {
    return error;
  }
  ADD_FAILURE() << "no DataError for: " << text;
  return DataError("", 0, 0, "");
}

TEST(LibsvmReader, ReadsSparseRowsAsDenseData) {
  const LabelledData data = read_text("1.5 1:0.5 3:-2\n-2 2:4e-1\n\n0 1:1 2:2 3:3\r\n");
  ASSERT_EQ(data.samples.rows(), 3);
  ASSERT_EQ(data.samples.cols(), 3);
  EXPECT_EQ(data.targets(0), 1.5);
  EXPECT_EQ(data.targets(1), -2);
  EXPECT_EQ(data.samples(0, 0), 0.5);
  EXPECT_EQ(data.samples(0, 1), 0);  // absent index
  EXPECT_EQ(data.samples(0, 2), -2);
  EXPECT_EQ(data.samples(1, 1), 0.4);
  EXPECT_EQ(data.samples(2, 2), 3);
}

TEST(LibsvmReader, RowWithoutFeaturesIsAllZeros) {
  const LabelledData data = read_text("3 2:1\n7\n");
  ASSERT_EQ(data.samples.rows(), 2);
  EXPECT_EQ(data.samples.row(1).squaredNorm(), 0);
  EXPECT_EQ(data.targets(1), 7);
}

TEST(LibsvmReader, BadLabelNamesLineAndColumn) {
  const DataError error = error_of("1 1:2\n  abc 1:2\n");
  EXPECT_EQ(error.line(), 2u);
  EXPECT_EQ(error.column(), 3u);
  EXPECT_NE(error.message().find("label"), std::string::npos);
  EXPECT_NE(std::string(error.what()).find("data.libsvm:2:3"), std::string::npos);
}

TEST(LibsvmReader, BadIndexNamesLineAndColumn) {
  DataError error = error_of("1 1:2 x:3\n");
  EXPECT_EQ(error.line(), 1u);
  EXPECT_EQ(error.column(), 7u);
  EXPECT_NE(error.message().find("index"), std::string::npos);
  error = error_of("1 0:2\n");
  EXPECT_EQ(error.column(), 3u);
  error = error_of("1 -1:2\n");
  EXPECT_EQ(error.column(), 3u);
}

TEST(LibsvmReader, NonIncreasingIndexNamesLineAndColumn) {
  DataError error = error_of("1 1:1\n2 1:1 3:2 2:5\n");
  EXPECT_EQ(error.line(), 2u);
  EXPECT_EQ(error.column(), 11u);
  EXPECT_NE(error.message().find("not greater"), std::string::npos);
  error = error_of("2 3:1 3:2\n");
  EXPECT_EQ(error.column(), 7u);
}

TEST(LibsvmReader, IndexAboveTheDenseBoundNamesLineAndColumn) {
  // Found by fuzzing: "0 999999999:1" asked for a 1 x 999,999,999 dense matrix.
  const DataError error = error_of("1 1:2\n0 2:1 999999999:1\n");
  EXPECT_EQ(error.line(), 2u);
  EXPECT_EQ(error.column(), 7u);
  EXPECT_NE(error.message().find("above the supported"), std::string::npos);
  const LabelledData data = read_text(fmt::format("1 {}:2\n", kMaxLibsvmFeatureIndex));
  EXPECT_EQ(data.samples.cols(), kMaxLibsvmFeatureIndex);
}

TEST(LibsvmReader, TooManyDenseValuesNamesTheLine) {
  // Rows x largest index past the bound: the line that crosses it is named.
  const long rows_at_bound = static_cast<long>(kMaxLibsvmDenseCells / kMaxLibsvmFeatureIndex);
  std::string text = fmt::format("1 {}:1\n", kMaxLibsvmFeatureIndex);
  for (long r = 1; r <= rows_at_bound; ++r) text += "0\n";
  const DataError error = error_of(text);
  EXPECT_EQ(error.line(), static_cast<std::size_t>(rows_at_bound + 1));
  EXPECT_NE(error.message().find("dense values"), std::string::npos);
}

TEST(LibsvmReader, MissingColonNamesLineAndColumn) {
  const DataError error = error_of("1 1:2\n\n1 1:2 5\n");
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 7u);
  EXPECT_NE(error.message().find("':'"), std::string::npos);
}

TEST(LibsvmReader, BadValuePointsAtTheValue) {
  const DataError error = error_of("1 10:abc\n");
  EXPECT_EQ(error.line(), 1u);
  EXPECT_EQ(error.column(), 6u);
  EXPECT_NE(error.message().find("value"), std::string::npos);
  EXPECT_EQ(error_of("1 1:nan\n").column(), 5u);
  EXPECT_EQ(error_of("1 1:\n").column(), 5u);
}

// A line is bounded while it is read: the reader stops just past the limit (it would have
// held a 50 MB line whole), names the line, and a line of exactly the limit still reads.
TEST(LibsvmReader, ALineLongerThanTheLimitIsRefusedWithoutReadingItWhole) {
  const std::string first = "1 1:2\n";
  std::istringstream input(first + std::string(5 * kMaxLibsvmLineBytes, '7') + "\n3 1:4\n");
  try {
    read_libsvm(input, "data.libsvm");
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& error) {
    EXPECT_EQ(error.line(), 2u);
    EXPECT_NE(std::string(error.what()).find("line longer than 1048576 bytes"), std::string::npos) << error.what();
    EXPECT_LT(std::string(error.what()).size(), 200u);
  }
  EXPECT_LE(static_cast<std::size_t>(input.tellg()), first.size() + kMaxLibsvmLineBytes + 1);

  std::string longest = "5 1:6";
  longest.resize(kMaxLibsvmLineBytes, ' ');
  const auto data = read_text(longest + "\n");
  ASSERT_EQ(data.targets.size(), 1);
  EXPECT_EQ(data.samples(0, 0), 6.0);
}

TEST(LibsvmReader, AStopRequestEndsTheRead) {
  std::string text;
  for (int i = 0; i < 10000; ++i) text += "1 1:2\n";
  std::atomic<bool> stop{true};
  std::istringstream input(text);
  EXPECT_THROW(read_libsvm(input, "data.libsvm", StopToken(stop)), Interrupted);
  std::istringstream again(text);
  EXPECT_EQ(read_libsvm(again, "data.libsvm").targets.size(), 10000);  // no token: read whole
}

TEST(LibsvmReader, EmptyFileIsAnError) {
  EXPECT_NE(std::string(error_of("").what()).find("no data"), std::string::npos);
  EXPECT_NE(std::string(error_of("\n  \n").what()).find("no data"), std::string::npos);
}

TEST(LibsvmReader, ReadsAFileAndRoundTripsWhatItWrites) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("thermodrift_libsvm_" + std::to_string(::getpid()) + ".txt");
  Eigen::MatrixXd samples{{0.1, -1.0 / 3}, {1e-300, 2.5}};
  Eigen::VectorXd targets{{3.25, -0.7}};
  {
    std::ofstream out(path);
    write_libsvm(out, samples, targets);
  }
  const LabelledData data = read_libsvm(path.string());
  std::filesystem::remove(path);
  EXPECT_EQ(data.samples, samples);
  EXPECT_EQ(data.targets, targets);
  EXPECT_THROW(read_libsvm((path.string() + ".missing")), DataError);
}

}  // namespace
}  // namespace thermodrift
