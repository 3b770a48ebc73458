// --out naming something other than a regular file: devices and FIFOs are written in
// place and stay what they are, symlinks stay links while their target is replaced, a
// failed write is one line and exit 1, and "" is a usage error. Device nodes and FIFOs
// are made in the test's own folder; the machine's /dev is never handed to the binary.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "../support/special_files.hpp"
#include "../support/one_line_error.hpp"
#include "../support/temp_dir.hpp"

namespace thermodrift {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::file_type;
using testing::read_file;
using testing::TempDir;

using testing::kBinary;
using testing::kTemps;

using testing::run_thermodrift;

using testing::expect_one_line;

// One simulated cycle, a linear model of it and its compensated log, made once.
class SpecialOutputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    shared_ = std::make_unique<TempDir>();
    auto result = run_thermodrift(*shared_, "simulate --cycles 1 --out sim.csv");
    ASSERT_EQ(result.status, 0) << result.err;
    result = run_thermodrift(*shared_, "fit --data sim.csv" + kTemps + " --model linear --out model.json");
    ASSERT_EQ(result.status, 0) << result.err;
    result = run_thermodrift(*shared_, "compensate --model model.json --data sim.csv --out compensated.csv");
    ASSERT_EQ(result.status, 0) << result.err;
    compensated_ = read_file(shared_->file("compensated.csv"));
  }
  static void TearDownTestSuite() { shared_.reset(); }

  void SetUp() override {
    dir_.write("sim.csv", read_file(shared_->file("sim.csv")));
    dir_.write("model.json", read_file(shared_->file("model.json")));
  }

  CommandResult compensate(const std::string& out) {
    return run_thermodrift(dir_, "compensate --model model.json --data sim.csv --out " + out);
  }

  static std::unique_ptr<TempDir> shared_;
  static std::string compensated_;
  TempDir dir_;
};

std::unique_ptr<TempDir> SpecialOutputs::shared_;
std::string SpecialOutputs::compensated_;

TEST_F(SpecialOutputs, ANullDeviceTakesTheOutputAndStaysADevice) {
  if (const auto why = testing::make_memory_device(dir_.file("null"), testing::kNullMinor); !why.empty()) {
    GTEST_SKIP() << why;
  }
  auto result = compensate("null");
  EXPECT_EQ(result.status, 0) << result.err;
  EXPECT_EQ(file_type(dir_.file("null")), S_IFCHR);
  result = run_thermodrift(dir_, "export --model model.json --out null");
  EXPECT_EQ(result.status, 0) << result.err;
  EXPECT_EQ(file_type(dir_.file("null")), S_IFCHR);
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"model.json", "null", "sim.csv"}));
}

TEST_F(SpecialOutputs, AFullDeviceIsExit1WithOneLine) {
  if (const auto why = testing::make_memory_device(dir_.file("full"), testing::kFullMinor); !why.empty()) {
    GTEST_SKIP() << why;
  }
  const auto result = run_thermodrift(dir_, "fit --data sim.csv" + kTemps + " --model linear --out full");
  EXPECT_EQ(result.status, 1) << result.err;
  expect_one_line(result);
  EXPECT_NE(result.err.find("No space left"), std::string::npos) << result.err;
  EXPECT_EQ(file_type(dir_.file("full")), S_IFCHR);
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"full", "model.json", "sim.csv"}));
}

// Results printed on the standard output (evaluate's table, fit --json, export's summary)
// that do not all reach it are exit 1 with one line, as with --out (they were exit 0).
TEST_F(SpecialOutputs, AStandardOutputThatCannotBeWrittenIsExit1) {
  if (const auto why = testing::make_memory_device(dir_.file("full"), testing::kFullMinor); !why.empty()) {
    GTEST_SKIP() << why;
  }
  for (const std::string& command : std::vector<std::string>{"evaluate --model model.json --data sim.csv", "export --model model.json --out model.h",
                                                               "fit --data sim.csv" + kTemps + " --model linear --json --out again.json"}) {
    SCOPED_TRACE(command);
    const auto result = testing::run_in(dir_, "( '" + kBinary + "' " + command + " > full )");
    EXPECT_EQ(result.status, 1) << result.err;
    EXPECT_NE(result.err.find("thermodrift: cannot write the standard output: No space left on device"),
              std::string::npos)
        << result.err;
    EXPECT_EQ(file_type(dir_.file("full")), S_IFCHR);
  }
}

TEST_F(SpecialOutputs, AFifoReaderGetsTheWholeOutput) {
  testing::make_fifo(dir_.file("pipe"));
  testing::FifoReader reader(dir_.file("pipe"));
  const auto result = compensate("pipe");
  EXPECT_EQ(result.status, 0) << result.err;
  const std::string& received = reader.finish();
  EXPECT_EQ(received.size(), compensated_.size());
  EXPECT_TRUE(received == compensated_);
  EXPECT_EQ(file_type(dir_.file("pipe")), S_IFIFO);
}

// A log refused before the first row is written: the FIFO's reader gets an end of file
// (it waited for ever when the output was opened only after the log's columns; for fit,
// whose model is written after minutes of work, only after the fit).
TEST_F(SpecialOutputs, AFifoReaderGetsAnEndOfFileWhenTheLogIsRefused) {
  for (const auto& [command, status] : std::vector<std::pair<std::string, int>>{
           {"compensate --model model.json --data sim.csv --gyro nosuch", 2},
           {"fit --data sim.csv --gyro nosuch --model linear", 3}}) {
    SCOPED_TRACE(command);
    testing::make_fifo(dir_.file("pipe"));
    const auto result = testing::run_in(dir_, "( timeout 20 cat pipe > got & '" + kBinary + "' " + command +
                                                  " --out pipe 2> err; echo \"tool $?\"; wait $!; echo \"reader $?\" )");
    EXPECT_EQ(result.out, fmt::format("tool {}\nreader 0\n", status)) << read_file(dir_.file("err"));
    EXPECT_EQ(read_file(dir_.file("got")), "");
    EXPECT_EQ(file_type(dir_.file("pipe")), S_IFIFO);
    fs::remove(dir_.file("pipe"));
  }
}

TEST_F(SpecialOutputs, AReaderThatLeavesEarlyIsAWriteErrorNotASilentDeath) {
  testing::make_fifo(dir_.file("pipe"));
  testing::FifoReader reader(dir_.file("pipe"), 1000);
  const auto result = compensate("pipe");
  reader.finish();
  EXPECT_EQ(result.status, 1) << result.err;  // -1 if SIGPIPE killed it
  expect_one_line(result);
  EXPECT_NE(result.err.find("Broken pipe"), std::string::npos) << result.err;
  EXPECT_EQ(file_type(dir_.file("pipe")), S_IFIFO);
}

TEST_F(SpecialOutputs, OurOwnStdoutThroughProcIsWrittenNotReplaced) {
  // As --out /dev/stdout with stdout redirected to a file: the link leads to that open file.
  fs::create_symlink("/proc/self/fd/1", dir_.file("stdout"));
  const auto result = compensate("stdout");
  EXPECT_EQ(result.status, 0) << result.err;
  EXPECT_TRUE(result.out == compensated_) << result.out.size() << " bytes, not " << compensated_.size();
  EXPECT_EQ(file_type(dir_.file("stdout")), S_IFLNK);
}

TEST_F(SpecialOutputs, ASymlinkStaysALinkAndItsTargetGetsTheOutput) {
  dir_.write("result.csv", "earlier result\n");
  fs::create_symlink("result.csv", dir_.file("latest.csv"));
  auto result = compensate("latest.csv");
  EXPECT_EQ(result.status, 0) << result.err;
  EXPECT_EQ(file_type(dir_.file("latest.csv")), S_IFLNK);
  EXPECT_TRUE(read_file(dir_.file("result.csv")) == compensated_);

  fs::create_directories(dir_.path() / "runs");
  fs::create_symlink("runs/next.csv", dir_.file("dangling.csv"));
  result = compensate("dangling.csv");
  EXPECT_EQ(result.status, 0) << result.err;
  EXPECT_EQ(file_type(dir_.file("dangling.csv")), S_IFLNK);
  EXPECT_TRUE(read_file(dir_.file("runs/next.csv")) == compensated_);
  EXPECT_EQ(dir_.entries(),
            (std::vector<std::string>{"dangling.csv", "latest.csv", "model.json", "result.csv", "runs", "sim.csv"}));
}

TEST_F(SpecialOutputs, ASymlinkToAnInputIsRefused) {
  const std::string before = read_file(dir_.file("sim.csv"));
  fs::create_symlink("sim.csv", dir_.file("out.csv"));
  const auto result = compensate("out.csv");
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);
  EXPECT_EQ(file_type(dir_.file("out.csv")), S_IFLNK);
  EXPECT_TRUE(read_file(dir_.file("sim.csv")) == before);
}

TEST_F(SpecialOutputs, AnEmptyOutIsAUsageError) {
  for (const std::string& command :
       {std::string("compensate --model model.json --data sim.csv --out ''"),
        "fit --data sim.csv" + kTemps + " --model linear --out ''", std::string("export --model model.json --out ''"),
        std::string("simulate --cycles 1 --out ''"), "report --data sim.csv" + kTemps + " --out ''"}) {
    const auto result = run_thermodrift(dir_, command);
    EXPECT_EQ(result.status, 2) << command << ": " << result.err;
    expect_one_line(result);
    EXPECT_NE(result.err.find("empty"), std::string::npos) << result.err;
  }
  EXPECT_EQ(dir_.entries(), (std::vector<std::string>{"model.json", "sim.csv"}));
}

TEST_F(SpecialOutputs, ReportIntoSomethingNotAFolderIsAUsageError) {
  testing::make_fifo(dir_.file("pipe"));
  const auto result = run_thermodrift(dir_, "report --data sim.csv" + kTemps + " --out pipe");
  EXPECT_EQ(result.status, 2) << result.err;
  expect_one_line(result);
  EXPECT_NE(result.err.find("pipe is a FIFO"), std::string::npos) << result.err;
  EXPECT_EQ(file_type(dir_.file("pipe")), S_IFIFO);
}

}  // namespace
}  // namespace thermodrift
