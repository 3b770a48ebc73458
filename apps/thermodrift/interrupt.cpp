#include "interrupt.hpp"

#include <csignal>
#include <cstdlib>

#include "thermodrift/error.hpp"

namespace thermodrift::cli {

namespace {
// The one piece of process-wide state: a signal handler can reach nothing else.
volatile std::sig_atomic_t interrupted = 0;

extern "C" void on_interrupt(int signal_number) {
  if (interrupted) std::_Exit(128 + signal_number);
  interrupted = 1;
}
}  // namespace

void install_interrupt_handler() {
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

bool interrupt_requested() { return interrupted != 0; }

void throw_if_interrupted() {
  if (interrupted) throw Interrupted("interrupted; no output written");
}

}  // namespace thermodrift::cli
