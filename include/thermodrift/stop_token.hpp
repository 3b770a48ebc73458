// Cancellation of long work (Ctrl-C in the CLI). The caller owns a flag — the CLI's is set
// by its SIGINT/SIGTERM handler — and hands every long library call a StopToken that
// reads it: feature identification, tuning, every SVR solve, the report's steps. Work
// asks the token between units of at most a fraction of a second and throws Interrupted,
// so it stops through the normal error path and no partial output is committed.
//
//   std::atomic<bool> stop{false};
//   CalibrationOptions options;
//   options.stop = StopToken(stop);   // another thread or a signal handler: stop = true
//
// A default token never stops. Asking is one relaxed atomic load, cheap in an inner loop;
// a lock-free std::atomic<bool> may be set from a signal handler.
#pragma once

#include <atomic>
#include <string>

#include "thermodrift/error.hpp"

namespace thermodrift {

class StopToken {
 public:
  StopToken() = default;
  explicit StopToken(const std::atomic<bool>& flag) : flag_(&flag) {}

  bool stop_requested() const { return flag_ != nullptr && flag_->load(std::memory_order_relaxed); }
  // Throws Interrupted("<what> stopped") once a stop was requested.
  void throw_if_requested(const char* what) const {
    if (stop_requested()) throw Interrupted(std::string(what) + " stopped");
  }

 private:
  const std::atomic<bool>* flag_ = nullptr;
};

}  // namespace thermodrift
