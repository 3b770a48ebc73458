#include "thermodrift/io/atomic_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <streambuf>
#include <string_view>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace fs = std::filesystem;

// Written by hand rather than with std::ofstream so that a failed write keeps its errno
// (ENOSPC, EPIPE) for the message, and so that the descriptor can be one that was opened
// without creating or truncating anything (a device, a FIFO, our own stdout).
class AtomicFile::Descriptor : public std::streambuf {
 public:
  explicit Descriptor(int descriptor) : descriptor_(descriptor) { reset_buffer(); }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  ~Descriptor() override {
    if (descriptor_ >= 0) ::close(descriptor_);
  }

  // Writes what is buffered and closes; returns 0 or the errno of the first failure.
  int close() {
    drain();
    if (descriptor_ >= 0 && ::close(descriptor_) != 0 && error_ == 0) error_ = errno;
    descriptor_ = -1;
    return error_;
  }

 protected:
  int_type overflow(int_type ch) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  // After the first failure the rest is dropped: the output is lost either way.
  bool drain() {
    for (const char* next = pbase(); error_ == 0 && next < pptr();) {
      const ssize_t written = ::write(descriptor_, next, static_cast<std::size_t>(pptr() - next));
      if (written >= 0) {
        next += written;
      } else if (errno != EINTR) {
        error_ = errno;
      }
    }
    reset_buffer();
    return error_ == 0;
  }
  void reset_buffer() { setp(buffer_.data(), buffer_.data() + buffer_.size()); }

  int descriptor_;
  int error_ = 0;
  std::array<char, 1 << 16> buffer_{};
};

namespace {

constexpr int kMaxSymlinks = 40;  // as the kernel's own limit for one path

void refuse_empty(const std::string& path) {
  if (path.empty()) throw UsageError("the output path is empty; name a file to write");
}

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISREG(mode)) return "a file";
  return "neither a file nor a device";
}

int open_in_place(const std::string& path, int flags) {
  const int descriptor = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY | flags);
  if (descriptor < 0) throw Error(fmt::format("cannot write {}: {}", path, std::strerror(errno)));
  return descriptor;
}

// A link in /proc names a file some process holds open; replacing it would leave that
// process writing to a file nobody can see. Our own descriptor (/dev/stdout) is shared,
// so that what we print there and what we write here stay in order.
int open_through_proc(const std::string& path, const fs::path& folder, const fs::path& name) {
  const std::string own = fmt::format("/proc/{}/fd", ::getpid());
  const std::string number = name.string();
  int own_descriptor = -1;
  const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), own_descriptor);
  if (folder == own && error == std::errc() && end == number.data() + number.size()) {
    const int descriptor = ::fcntl(own_descriptor, F_DUPFD_CLOEXEC, 0);
    if (descriptor < 0) throw Error(fmt::format("cannot write {}: {}", path, std::strerror(errno)));
    return descriptor;
  }
  return open_in_place(path, O_TRUNC);
}

// Where an output goes: either a file to replace, or a descriptor to write in place.
struct Destination {
  std::string replace;  // the regular file (or new name) to rename onto; empty: in place
  int descriptor = -1;
};

Destination resolve(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) == 0) {
    if (S_ISDIR(status.st_mode)) throw UsageError(fmt::format("output {} is a directory", path));
    if (S_ISCHR(status.st_mode) || S_ISFIFO(status.st_mode)) return {"", open_in_place(path, 0)};
    if (!S_ISREG(status.st_mode)) {
      throw UsageError(fmt::format("output {} is {}; refusing to write to it", path, kind_of(status.st_mode)));
    }
  } else if (errno == ELOOP) {
    throw UsageError(fmt::format("output {}: too many levels of symbolic links", path));
  }
  // A regular file or nothing yet: follow the links to the file that is to be replaced.
  fs::path current = path;
  for (int links = 0; links <= kMaxSymlinks; ++links) {
    std::error_code error;
    const fs::path folder = fs::canonical(current.has_parent_path() ? current.parent_path() : ".", error);
    if (error) return {current.string()};  // creating the temporary file will say what is wrong
    current = folder / current.filename();
    if (folder.string().starts_with("/proc/")) return {"", open_through_proc(path, folder, current.filename())};
    struct stat link {};
    if (::lstat(current.c_str(), &link) != 0) return {current.string()};
    if (!S_ISLNK(link.st_mode)) {
      // Renaming needs only the folder's permission; a file its owner made read-only is
      // kept as `cp` would keep it (root may write any file, and does).
      if (::access(current.c_str(), W_OK) != 0 && errno == EACCES) {
        throw Error(fmt::format("cannot write {}: the file is read-only; make it writable or choose another "
                                "output",
                                path));
      }
      return {current.string()};
    }
    const fs::path next = fs::read_symlink(current, error);
    if (error) throw Error(fmt::format("cannot read the link {}: {}", current.string(), error.message()));
    current = next.is_absolute() ? next : folder / next;
  }
  throw UsageError(fmt::format("output {}: too many levels of symbolic links", path));
}

}  // namespace

void refuse_overwriting_inputs(const std::string& output, const std::vector<std::string>& inputs) {
  struct stat status {};
  // Reading and writing the same device or pipe is the caller's business; a file is data.
  if (::stat(output.c_str(), &status) != 0 || !S_ISREG(status.st_mode)) return;
  std::error_code ignored;
  for (const auto& input : inputs) {
    if (fs::equivalent(output, input, ignored)) {
      throw UsageError(fmt::format("output {} is one of the inputs; refusing to overwrite it", output));
    }
  }
}

void check_output_folder(const std::string& folder) {
  if (folder.empty()) throw UsageError("the output folder is empty; name a folder to write");
  struct stat status {};
  if (::stat(folder.c_str(), &status) == 0 && !S_ISDIR(status.st_mode)) {
    throw UsageError(fmt::format("output folder {} is {}", folder, kind_of(status.st_mode)));
  }
}

AtomicFile::AtomicFile(std::string path, const std::vector<std::string>& inputs)
    : path_(std::move(path)), stream_(nullptr) {
  refuse_empty(path_);
  refuse_overwriting_inputs(path_, inputs);
  const Destination destination = resolve(path_);
  int descriptor = destination.descriptor;
  if (!destination.replace.empty()) {
    target_path_ = destination.replace;
    const fs::path target(target_path_);
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    std::string pattern = (folder / ("." + target.filename().string() + ".tmp-XXXXXX")).string();
    descriptor = ::mkostemp(pattern.data(), O_CLOEXEC);
    if (descriptor < 0) throw Error(fmt::format("cannot write {}: {}", path_, std::strerror(errno)));
    temporary_path_ = pattern;
  }
  buffer_ = std::make_unique<Descriptor>(descriptor);
  stream_.rdbuf(buffer_.get());
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    buffer_.reset();
    if (!temporary_path_.empty()) std::remove(temporary_path_.c_str());
  }
}

void AtomicFile::commit() {
  stream_.flush();
  const int error = buffer_->close();
  if (error != 0) throw Error(fmt::format("cannot write {}: {}", path_, std::strerror(error)));
  if (!stream_) throw Error(fmt::format("cannot write {}: the output stream failed", path_));
  if (!in_place()) {
    // mkstemp creates 0600: a file replaced keeps its permissions, a new one gets the
    // usual 0644.
    struct stat existing {};
    const bool replacing = ::stat(target_path_.c_str(), &existing) == 0 && S_ISREG(existing.st_mode);
    ::chmod(temporary_path_.c_str(), replacing ? (existing.st_mode & 07777) : 0644);
    if (std::rename(temporary_path_.c_str(), target_path_.c_str()) != 0) {
      throw Error(fmt::format("cannot move the output into place at {}: {}", path_, std::strerror(errno)));
    }
  }
  committed_ = true;
}

void write_file_atomically(const std::string& path, const std::string& text,
                           const std::vector<std::string>& inputs) {
  AtomicFile file(path, inputs);
  file.stream() << text;
  file.commit();
}

namespace {

// DIR without a trailing separator ("out/" names the folder "out").
fs::path folder_path(const std::string& folder) {
  fs::path path = fs::path(folder).lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();
  return path;
}

// Writes every file under `from` to the same place under `to`, each under AtomicFile's rule.
void write_tree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (const auto& entry : fs::directory_iterator(from)) {
    const fs::path target = to / entry.path().filename();
    if (entry.is_directory()) {
      write_tree(entry.path(), target);
      continue;
    }
    std::ifstream in(entry.path(), std::ios::binary);
    if (!in) throw Error(fmt::format("cannot read {}", entry.path().string()));
    AtomicFile out(target.string());
    // Inserting a streambuf that yields nothing sets failbit: an empty file (gnuplot's log
    // when it had nothing to say) is an empty file, not a failed write.
    if (in.peek() != std::ifstream::traits_type::eof()) out.stream() << in.rdbuf();
    if (in.bad()) throw Error(fmt::format("cannot read {}", entry.path().string()));
    out.commit();
  }
}

// Staging folders of DIR (.DIR.partial-PID-N) whose process is gone: a second Ctrl-C
// ends the tool at once (std::_Exit from the signal handler, which can run no clean-up),
// and a killed process leaves its staging folder too. The next run into DIR removes them.
// A folder of a process still running (another run into DIR) is left alone.
void remove_abandoned_staging(const fs::path& parent, const std::string& name) {
  const std::string prefix = "." + name + ".partial-";
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(parent, error)) {
    const std::string entry_name = entry.path().filename().string();
    if (entry_name.rfind(prefix, 0) != 0) continue;
    const std::string_view rest = std::string_view(entry_name).substr(prefix.size());
    long pid = 0;
    const auto [end, parsed] = std::from_chars(rest.data(), rest.data() + rest.size(), pid);
    if (parsed != std::errc{} || end == rest.data() || end == rest.data() + rest.size() || *end != '-' || pid <= 0) {
      continue;
    }
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge
    // A folder output staged inside another (demo's report) has its staging folder beside
    // that one: ..DIR.partial-PID-N.partial-PID-M.
    remove_abandoned_staging(parent, entry_name);
    std::error_code ignored;
    fs::remove_all(entry.path(), ignored);
  }
}

}  // namespace

StagedFolder::StagedFolder(std::string folder) : folder_(std::move(folder)) {
  check_output_folder(folder_);
  const fs::path path = folder_path(folder_);
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  remove_abandoned_staging(parent, path.filename().string());
  // mkdir, not mkdtemp: the folder gets the permissions the umask gives a new folder,
  // which it keeps when it is renamed to DIR.
  for (int attempt = 0;; ++attempt) {
    const std::string name = fmt::format(".{}.partial-{}-{}", path.filename().string(), ::getpid(), attempt);
    staging_ = (parent / name).string();
    if (::mkdir(staging_.c_str(), 0777) == 0) return;
    if (errno != EEXIST || attempt == 100) {
      const int error = errno;
      staging_.clear();
      throw Error(fmt::format("cannot write {}: {}", folder_, std::strerror(error)));
    }
  }
}

StagedFolder::~StagedFolder() {
  if (committed_ || staging_.empty()) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

std::string StagedFolder::committed_path(const std::string& staged) const {
  return (fs::path(folder_) / fs::path(staged).lexically_relative(staging_)).string();
}

void StagedFolder::commit() {
  const fs::path path = folder_path(folder_);
  // A folder that does not exist yet appears whole, in one rename; an existing one (or
  // one made meanwhile: EEXIST, ENOTEMPTY) gets the files one by one.
  if (!fs::exists(path) && ::rename(staging_.c_str(), path.c_str()) == 0) {
    committed_ = true;
    return;
  }
  write_tree(staging_, path);
  committed_ = true;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

}  // namespace thermodrift
