// Ctrl-C: the first SIGINT/SIGTERM sets a flag that every long library call reads through
// the StopToken it is given, so the command stops within a second through the normal
// error path (temporary outputs removed) and exits 128 + the signal's number (130 for
// SIGINT, 143 for SIGTERM); a second signal ends the process at once.
#pragma once

#include "thermodrift/stop_token.hpp"

namespace thermodrift::cli {

void install_interrupt_handler();
// The token of the flag the handler sets (or set_interrupted).
StopToken interrupt_token();
// Whether that flag is set: an error met after it (a call the signal cut short) ends the
// command as interrupted.
bool interrupt_requested();
// Sets or clears that flag without a signal: an embedding (the Python package) that runs
// a command and catches Ctrl-C itself.
void set_interrupted(bool interrupted);
// The exit status of a command stopped by Interrupted: 128 + the signal received, 130
// when the stop came from elsewhere (a callback).
int interrupted_exit_status();

}  // namespace thermodrift::cli
