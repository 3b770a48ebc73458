// Exit statuses of the command-line tool (docs/cli.md): a CLI concept, so here and not in
// the library, which only throws typed errors (thermodrift/error.hpp).
#pragma once

namespace thermodrift::cli {

enum class ExitStatus : int { ok = 0, failure = 1, usage = 2, bad_data = 3, interrupted = 130 };

}  // namespace thermodrift::cli
