#include "interrupt.hpp"
#include "exit_status.hpp"

#include <atomic>
#include <csignal>
#include <cstdlib>

#include "thermodrift/error.hpp"

namespace thermodrift::cli {

namespace {
// The one piece of process-wide state: a signal handler can reach nothing else. Lock-free
// atomics are safe to set from a handler.
std::atomic<bool> interrupted{false};
std::atomic<int> received_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free);

extern "C" void on_interrupt(int signal_number) {
  if (interrupted.load()) std::_Exit(128 + signal_number);
  received_signal.store(signal_number);
  interrupted.store(true);
}
}  // namespace

void install_interrupt_handler() {
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

StopToken interrupt_token() { return StopToken(interrupted); }

void set_interrupted(bool value) { interrupted.store(value); }

int interrupted_exit_status() {
  const int signal_number = received_signal.load();
  return signal_number > 0 ? 128 + signal_number : static_cast<int>(ExitStatus::interrupted);
}

}  // namespace thermodrift::cli
