// Ctrl-C (SIGINT) and SIGTERM stop the long commands: exit 130 / 143, soon after the
// signal, and nothing left at --out (docs/cli.md, "Exit statuses and stopping"). The
// bound is generous (3 s; the aim is 1 s) because the machines running the tests are
// shared: this checks that the command stops, not how fast.
#include <gtest/gtest.h>

#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include "../support/child_process.hpp"
#include "../support/temp_dir.hpp"

namespace thermodrift {
namespace {

using testing::ChildProcess;
using testing::TempDir;

constexpr auto kRunBeforeSignal = std::chrono::seconds(2);
constexpr double kStopWithinSeconds = 3.0;

const std::vector<std::string> kLogColumns{"--time", "time_s", "--gyro", "gyro_x,gyro_y,gyro_z",
                                           "--temp", "temp_x,temp_y,temp_z"};

// A simulated log small enough to keep the set-up quick, long enough that every command
// below is still working when the signal arrives.
void simulate_log(const TempDir& dir) {
  const auto simulated = testing::run_thermodrift(dir, "simulate --out chamber.csv --cycles 2 --rate 0.2");
  ASSERT_EQ(simulated.status, 0) << simulated.err;
}

std::vector<std::string> with_log(std::vector<std::string> arguments) {
  arguments.insert(arguments.end(), kLogColumns.begin(), kLogColumns.end());
  return arguments;
}

// Runs thermodrift with `arguments` in `dir`, sends `signal_number` after a while and
// checks the exit status, the time to stop and that `dir` holds what it held before.
void expect_stops(const TempDir& dir, const std::vector<std::string>& arguments, int signal_number,
                  int expected_status) {
  std::vector<std::string> before = dir.entries();
  ChildProcess child(dir, THERMODRIFT_BINARY, arguments);
  std::this_thread::sleep_for(kRunBeforeSignal);
  ASSERT_TRUE(child.running()) << "finished before the signal; make the work longer: " << child.stderr_text();
  child.signal(signal_number);
  const auto status = child.wait_for(std::chrono::seconds(30));
  ASSERT_TRUE(status.has_value()) << "still running 30 s after the signal";
  EXPECT_EQ(*status, expected_status) << child.stderr_text();
  EXPECT_LT(child.seconds_to_stop(), kStopWithinSeconds) << child.stderr_text();
  EXPECT_NE(child.stderr_text().find("interrupted"), std::string::npos) << child.stderr_text();
  std::vector<std::string> after;
  for (const auto& name : dir.entries()) {
    if (name != ".stdout.child" && name != ".stderr.child") after.push_back(name);
  }
  std::erase(before, ".stdout.child");
  std::erase(before, ".stderr.child");
  EXPECT_EQ(after, before) << "something was left beside or at --out";
  std::fprintf(stderr, "stopped %.3f s after the signal (ran %.1f s)\n", child.seconds_to_stop(), child.seconds_run());
}

TEST(Cancel, DemoStopsOnCtrlCAndCreatesNoFolder) {
  TempDir dir;
  expect_stops(dir, {"demo", "--out", "demo-out"}, SIGINT, 130);
}

TEST(Cancel, ReportStopsOnCtrlCAndCreatesNoFolder) {
  TempDir dir;
  simulate_log(dir);
  expect_stops(dir, with_log({"report", "--data", "chamber.csv", "--out", "report-out"}), SIGINT, 130);
}

TEST(Cancel, ReportStopsOnSigtermAndAddsNothingToAnExistingFolder) {
  TempDir dir;
  simulate_log(dir);
  std::filesystem::create_directory(dir.path() / "report-out");
  dir.write("report-out/report.html", "an earlier report");
  expect_stops(dir, with_log({"report", "--data", "chamber.csv", "--out", "report-out"}), SIGTERM, 143);
  std::vector<std::string> inside;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path() / "report-out")) {
    inside.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(inside, std::vector<std::string>{"report.html"});
  EXPECT_EQ(testing::read_file(dir.file("report-out/report.html")), "an earlier report");
}

TEST(Cancel, FitWithFeatureIdentificationStopsOnCtrlC) {
  TempDir dir;
  simulate_log(dir);
  expect_stops(dir, with_log({"fit", "--data", "chamber.csv", "--model", "svr", "--features", "auto", "--out", "model.json"}),
               SIGINT, 130);
}

TEST(Cancel, FitWithTheGreedySearchStopsOnSigterm) {
  TempDir dir;
  simulate_log(dir);
  expect_stops(dir,
               with_log({"fit", "--data", "chamber.csv", "--model", "svr", "--features", "auto", "--identify", "greedy",
                         "--out", "model.json"}),
               SIGTERM, 143);
}

TEST(Cancel, SimulateStopsOnCtrlCAndWritesNoLog) {
  TempDir dir;
  // 4.5 million rows: several seconds of simulating and writing.
  expect_stops(dir, {"simulate", "--out", "long.csv", "--cycles", "20", "--rate", "10"}, SIGINT, 130);
}

}  // namespace
}  // namespace thermodrift
