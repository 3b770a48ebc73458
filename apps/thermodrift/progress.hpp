// Progress of long work on stderr: a one-line bar redrawn in place when stderr is a
// terminal, plain lines (at most one a second) otherwise. stdout is never touched.
#pragma once

#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

#include "thermodrift/optim/optimizer.hpp"

namespace thermodrift::cli {

class ProgressPrinter {
 public:
  explicit ProgressPrinter(std::string what);
  ~ProgressPrinter();  // ends a bar with a newline

  // Shows the tuning of axis `axis` of `axes`; always true (Ctrl-C reaches the tuning
  // through CalibrationOptions::stop).
  bool tuning(std::size_t axis, std::size_t axes, const optim::Progress& progress);
  // One line of a step outside tuning ("choosing feature terms"), ending a bar first.
  void step(std::size_t axis, std::size_t axes, const std::string& what);

 private:
  std::mutex mutex_;  // the axes are fitted in parallel
  std::string what_;
  bool terminal_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_line_{};
};

}  // namespace thermodrift::cli
