#include "progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>


namespace thermodrift::cli {

ProgressPrinter::ProgressPrinter(std::string what)
    : what_(std::move(what)), terminal_(::isatty(STDERR_FILENO) == 1) {}

ProgressPrinter::~ProgressPrinter() {
  if (drawn_) std::fputc('\n', stderr);
}

bool ProgressPrinter::tuning(std::size_t axis, std::size_t axes, const optim::Progress& progress) {
  const std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  const double done = (static_cast<double>(axis) + progress.fraction_done) / static_cast<double>(axes);
  const double left = done > 0.01 ? progress.elapsed_seconds / progress.fraction_done * (1 - progress.fraction_done) : 0;
  if (terminal_) {
    constexpr int kWidth = 24;
    const int filled = static_cast<int>(done * kWidth);
    fmt::print(stderr, "\r{} [{:<{}}] axis {}/{} iter {} evals {} best {:.3g} ~{:.0f}s left in its tuning  ", what_,
               std::string(static_cast<std::size_t>(std::max(0, std::min(kWidth, filled))), '#'), kWidth,
               axis + 1, axes, progress.iteration, progress.evaluations, progress.best_value, left);
    drawn_ = true;
  } else if (now - last_line_ >= std::chrono::seconds(1)) {
    fmt::print(stderr, "{}: axis {}/{} iteration {} evaluations {} best {:.4g} ({:.0f} % of the axis' tuning, ~{:.0f} s left in it)\n",
               what_, axis + 1, axes, progress.iteration, progress.evaluations, progress.best_value,
               100 * progress.fraction_done, left);
    last_line_ = now;
  }
  return true;
}

void ProgressPrinter::step(std::size_t axis, std::size_t axes, const std::string& what) {
  const std::lock_guard lock(mutex_);
  if (drawn_) std::fputc('\n', stderr);
  drawn_ = false;
  fmt::print(stderr, "{}: axis {}/{}: {}\n", what_, axis + 1, axes, what);
}

}  // namespace thermodrift::cli
