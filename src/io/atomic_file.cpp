#include "thermodrift/io/atomic_file.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace fs = std::filesystem;

void refuse_overwriting_inputs(const std::string& output, const std::vector<std::string>& inputs) {
  std::error_code ignored;
  for (const auto& input : inputs) {
    if (fs::exists(output, ignored) && fs::equivalent(output, input, ignored)) {
      throw UsageError(fmt::format("output {} is one of the inputs; refusing to overwrite it", output));
    }
  }
}

AtomicFile::AtomicFile(std::string path, const std::vector<std::string>& inputs)
    : path_(std::move(path)) {
  refuse_overwriting_inputs(path_, inputs);
  if (fs::is_directory(path_)) throw UsageError(fmt::format("output {} is a directory", path_));
  const fs::path target(path_);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string pattern = (folder / ("." + target.filename().string() + ".tmp-XXXXXX")).string();
  const int descriptor = ::mkstemp(pattern.data());
  if (descriptor < 0) {
    throw Error(fmt::format("cannot write {}: {}", path_, std::strerror(errno)));
  }
  ::close(descriptor);
  temporary_path_ = pattern;
  stream_.open(temporary_path_, std::ios::binary | std::ios::trunc);
  if (!stream_) {
    std::remove(temporary_path_.c_str());
    throw Error(fmt::format("cannot write {}", path_));
  }
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    stream_.close();
    std::remove(temporary_path_.c_str());
  }
}

void AtomicFile::commit() {
  stream_.flush();
  stream_.close();
  if (!stream_) throw Error(fmt::format("writing {} failed (disk full?)", path_));
  // mkstemp creates 0600; a result file should carry the usual permissions.
  std::error_code ignored;
  fs::permissions(temporary_path_,
                  fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                      fs::perms::others_read,
                  ignored);
  if (std::rename(temporary_path_.c_str(), path_.c_str()) != 0) {
    throw Error(fmt::format("cannot move the output into place at {}: {}", path_,
                            std::strerror(errno)));
  }
  committed_ = true;
}

void write_file_atomically(const std::string& path, const std::string& text,
                           const std::vector<std::string>& inputs) {
  AtomicFile file(path, inputs);
  file.stream() << text;
  file.commit();
}

}  // namespace thermodrift
