// write_report, called as a library, writes its folder whole or not at all (the CLI's
// report and demo did this themselves; a caller of the library got a half-written folder
// when a step failed or was stopped).
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "../../support/temp_dir.hpp"
#include "thermodrift/report/report.hpp"
#include "thermodrift/sim/simulator.hpp"

namespace thermodrift {
namespace {

namespace fs = std::filesystem;

std::set<std::string> names_in(const fs::path& folder) {
  std::set<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    names.insert(entry.path().lexically_relative(folder).string());
  }
  return names;
}

class WriteReport : public ::testing::Test {
 protected:
  void SetUp() override {
    sim::SimulatorOptions simulator;
    simulator.rate_hz = 0.1;
    log_ = sim::to_chamber_log(sim::simulate(simulator));
    options_.study.models = {ModelKind::linear, ModelKind::stepwise};  // no SVR: a quick study
    options_.gnuplot = "";                            // no figures
    options_.study.calibration.stop = StopToken(stop_);
  }
  testing::TempDir dir_;
  ChamberLog log_;
  ReportOptions options_;
  std::atomic<bool> stop_{false};
};

TEST_F(WriteReport, AStoppedReportLeavesAnExistingFolderAsItWas) {
  const fs::path folder = dir_.file("report");
  fs::create_directories(folder);
  std::ofstream(folder / "notes.txt") << "mine\n";
  std::ofstream(folder / "report.html") << "an older report\n";
  options_.out_dir = folder.string();
  // Stop once the models are being written: some files of the new report exist by then.
  options_.progress = [&](const std::string& line) {
    if (line.find("figures") != std::string::npos) stop_ = true;
  };
  EXPECT_THROW(write_report(log_, {}, options_), Interrupted);
  EXPECT_EQ(names_in(folder), (std::set<std::string>{"notes.txt", "report.html"}));
  std::ifstream html(folder / "report.html");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(html), {}), "an older report\n");
  // and nothing is left beside it
  EXPECT_EQ(names_in(dir_.path()), (std::set<std::string>{"report", "report/notes.txt", "report/report.html"}));
}

TEST_F(WriteReport, AFinishedReportAppearsWholeAndKeepsOtherFiles) {
  const fs::path folder = dir_.file("nested/report");  // parents are made
  options_.out_dir = folder.string();
  const ReportResult result = write_report(log_, {}, options_);
  EXPECT_EQ(result.html_path, (folder / "report.html").string());
  EXPECT_EQ(result.summary_path, (folder / "summary.json").string());
  const auto names = names_in(folder);
  for (const char* name : {"report.html", "summary.json", "model_linear.json", "model_stepwise.json"}) {
    EXPECT_EQ(names.count(name), 1u) << name;
  }
  std::ofstream(folder / "notes.txt") << "mine\n";
  write_report(log_, {}, options_);
  EXPECT_EQ(names_in(folder).count("notes.txt"), 1u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_.file("nested")), fs::directory_iterator()), 1);  // no staging left
}

}  // namespace
}  // namespace thermodrift
