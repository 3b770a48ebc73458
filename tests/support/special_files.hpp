// Special files for the output tests, made only inside a test's own temporary folder: a
// device node (a private "null" or "full" device), a FIFO and its reader. The machine's own
// /dev entries are never handed to the code under test.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>

namespace thermodrift::testing {

// Device numbers of Linux's memory devices (Documentation/admin-guide/devices.txt).
inline constexpr unsigned kNullMinor = 3;  // /dev/null: swallows every write
inline constexpr unsigned kFullMinor = 7;  // /dev/full: every write fails with ENOSPC

// Makes a character device node for memory device `minor` at `path`. Returns "" or why
// it could not (no CAP_MKNOD, a nodev mount), for GTEST_SKIP.
inline std::string make_memory_device(const std::string& path, unsigned minor) {
  if (::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, minor)) != 0) {
    return "cannot make a device node (" + std::string(std::strerror(errno)) + ")";
  }
  // A folder mounted nodev holds the node but refuses to open it.
  const int probe = ::open(path.c_str(), O_WRONLY);
  if (probe < 0) return "cannot open a device node here (" + std::string(std::strerror(errno)) + ")";
  ::close(probe);
  return "";
}

inline mode_t file_type(const std::string& path) {
  struct stat status {};
  return ::lstat(path.c_str(), &status) == 0 ? (status.st_mode & S_IFMT) : 0;
}

inline void make_fifo(const std::string& path) {
  if (::mkfifo(path.c_str(), 0600) != 0) throw std::runtime_error("mkfifo " + path + ": " + std::strerror(errno));
}

// Reads a FIFO on its own thread until the writer is done, or until `limit` bytes have
// arrived (then closes early, so that the writer meets EPIPE). Opened without blocking, so
// a writer that never opens the FIFO makes the test fail instead of hang: call finish()
// once the writer has returned.
class FifoReader {
 public:
  explicit FifoReader(const std::string& path, std::size_t limit = std::string::npos) : limit_(limit) {
    // CLOEXEC: a writer started from this process must not inherit a read end.
    descriptor_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (descriptor_ < 0) throw std::runtime_error("open " + path + ": " + std::strerror(errno));
    thread_ = std::thread([this] { read_all(); });
  }
  FifoReader(const FifoReader&) = delete;
  FifoReader& operator=(const FifoReader&) = delete;
  ~FifoReader() { finish(); }

  // Waits for the reader after the writer has finished; returns what arrived.
  const std::string& finish() {
    writer_done_ = true;
    if (thread_.joinable()) thread_.join();
    return received_;
  }

 private:
  void read_all() {
    char buffer[1 << 16];
    while (received_.size() < limit_) {
      const bool writer_was_done = writer_done_;  // read before, so that a 0 after it means drained
      const ssize_t count = ::read(descriptor_, buffer, sizeof buffer);
      if (count > 0) {
        received_.append(buffer, static_cast<std::size_t>(count));
      } else if (count == 0 && writer_was_done) {
        break;  // no writer now, and none to come
      } else {
        // Empty (EAGAIN), or no writer yet / between writers (0): wait a little.
        pollfd wait{descriptor_, POLLIN, 0};
        ::poll(&wait, 1, 10);
        if (count == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
    ::close(descriptor_);
  }

  std::size_t limit_;
  int descriptor_ = -1;
  std::atomic<bool> writer_done_{false};
  std::string received_;
  std::thread thread_;
};

}  // namespace thermodrift::testing
