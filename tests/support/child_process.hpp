// A command run in the background, for tests that signal it (Ctrl-C, SIGTERM) and time
// how long it takes to stop. The parent reaps it with waitpid, so the time measured ends
// when the process has exited, not when it became a zombie.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "temp_dir.hpp"

namespace thermodrift::testing {

class ChildProcess {
 public:
  using Clock = std::chrono::steady_clock;

  // Starts `program arguments...` in `dir`, stdout and stderr to files there
  // (.stdout.child, .stderr.child).
  ChildProcess(const TempDir& dir, const std::string& program, const std::vector<std::string>& arguments)
      : err_path_(dir.file(".stderr.child")) {
    std::vector<std::string> words{program};
    words.insert(words.end(), arguments.begin(), arguments.end());
    std::vector<char*> argv;
    for (auto& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);
    const std::string folder = dir.path().string();
    const std::string out_path = dir.file(".stdout.child");
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {  // only async-signal-safe calls until exec
      const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = ::open(err_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (::chdir(folder.c_str()) != 0 || out < 0 || err < 0) ::_exit(127);
      ::dup2(out, STDOUT_FILENO);
      ::dup2(err, STDERR_FILENO);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    started_ = Clock::now();
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() {
    if (!reaped_) {
      ::kill(pid_, SIGKILL);
      int ignored = 0;
      ::waitpid(pid_, &ignored, 0);
    }
  }

  // Sends `signal_number` and remembers when.
  void signal(int signal_number) {
    signalled_ = Clock::now();
    ::kill(pid_, signal_number);
  }

  // True while the process has not exited (reaps it when it has).
  bool running() { return !reaped_ && !poll(); }

  // Waits at most `limit` for the exit; its status, or -(signal) when a signal ended it;
  // nullopt when it is still running.
  std::optional<int> wait_for(std::chrono::duration<double> limit) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(limit);
    while (!reaped_ && !poll()) {
      if (Clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return status_;
  }

  // Seconds from signal() to the exit seen by wait_for (within its 5 ms polling).
  double seconds_to_stop() const { return std::chrono::duration<double>(ended_ - signalled_).count(); }
  double seconds_run() const { return std::chrono::duration<double>(ended_ - started_).count(); }
  std::string stderr_text() const { return read_file(err_path_); }

 private:
  bool poll() {
    int raw = 0;
    const pid_t done = ::waitpid(pid_, &raw, WNOHANG);
    if (done != pid_) return false;
    ended_ = Clock::now();
    reaped_ = true;
    status_ = WIFEXITED(raw) ? WEXITSTATUS(raw) : -WTERMSIG(raw);
    return true;
  }

  std::string err_path_;
  pid_t pid_ = -1;
  bool reaped_ = false;
  int status_ = -1;
  Clock::time_point started_, signalled_, ended_;
};

}  // namespace thermodrift::testing
