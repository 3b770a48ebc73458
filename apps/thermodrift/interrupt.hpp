// Ctrl-C: the first SIGINT/SIGTERM sets a flag that long work polls, so the command
// stops within a second through the normal error path (temporary outputs removed);
// a second one ends the process at once.
#pragma once

namespace thermodrift::cli {

void install_interrupt_handler();
bool interrupt_requested();
// Throws Interrupted if an interrupt was requested.
void throw_if_interrupted();

}  // namespace thermodrift::cli
