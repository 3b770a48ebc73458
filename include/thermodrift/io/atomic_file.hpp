// Output files that appear whole or not at all: written to a temporary file beside the
// target and renamed into place on commit(), so a failure or an interrupt leaves the old
// file (or none), never half a file.
#pragma once

#include <fstream>
#include <string>
#include <vector>

namespace thermodrift {

class AtomicFile {
 public:
  // Opens a temporary file in the target's folder. Throws UsageError if `path` is one of
  // `inputs` (an output must never overwrite the data it is made from), Error if the
  // folder cannot be written.
  explicit AtomicFile(std::string path, const std::vector<std::string>& inputs = {});
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();  // removes the temporary file unless committed

  std::ostream& stream() { return stream_; }
  const std::string& path() const { return path_; }

  // Flushes, checks that every write succeeded, and renames into place.
  void commit();

 private:
  std::string path_;
  std::string temporary_path_;
  std::ofstream stream_;
  bool committed_ = false;
};

// Throws UsageError if `output` names the same file as one of `inputs`.
void refuse_overwriting_inputs(const std::string& output, const std::vector<std::string>& inputs);

// Writes `text` to `path` atomically.
void write_file_atomically(const std::string& path, const std::string& text,
                           const std::vector<std::string>& inputs = {});

}  // namespace thermodrift
