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
  // Without SA_RESTART: a call blocked in the kernel (opening a FIFO nobody reads, a pipe
  // that is full) returns EINTR at the first signal instead of waiting on past it.
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool interrupt_requested() { return interrupted.load(); }

StopToken interrupt_token() { return StopToken(interrupted); }

void set_interrupted(bool value) { interrupted.store(value); }

int interrupted_exit_status() {
  const int signal_number = received_signal.load();
  return signal_number > 0 ? 128 + signal_number : static_cast<int>(ExitStatus::interrupted);
}

}  // namespace thermodrift::cli
