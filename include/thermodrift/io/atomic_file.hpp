// Output files that appear whole or not at all — and outputs that are not files.
//
// The rule for an output path (every `--out` of the CLI goes through it; docs/design.md):
// - "" is a usage error; so is a directory.
// - The path is stat()ed, following symlinks. A character device (/dev/null, a terminal)
//   or a FIFO (a named pipe, `--out /dev/stdout` in a pipeline) is opened and written
//   directly: its reader gets the bytes, and a failed write (ENOSPC as on /dev/full,
//   EPIPE) is an Error. Whatever reached it before a failure has reached it.
// - A block device, a socket or any other kind of file is refused (UsageError).
// - A regular file, or a name that does not exist yet, is replaced atomically: written to
//   a temporary file beside it and renamed into place on commit(), so a failure or an
//   interrupt leaves the old file (or none), never half a file. A replaced file keeps its
//   permissions; a new one gets 0644.
// - A symlink is followed (up to 40 links; a relative link is read against the link's
//   folder) and its final target is the file replaced — the link stays a link, and a
//   dangling link gets its target created. Nothing but a regular file is ever renamed over.
// - A link into /proc (as /dev/stdout, /dev/fd/N are) names a file a process holds open:
//   it is written through that open file, not replaced.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace thermodrift {

class AtomicFile {
 public:
  // Opens the output under the rule above. Throws UsageError if `path` is empty, a
  // directory, a kind of file that is refused, or one of `inputs` (an output must never
  // overwrite the data it is made from), Error if it cannot be written.
  explicit AtomicFile(std::string path, const std::vector<std::string>& inputs = {});
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();  // removes the temporary file unless committed

  std::ostream& stream() { return stream_; }
  const std::string& path() const { return path_; }
  // True when the output is written directly (a device, a pipe), not replaced on commit().
  bool in_place() const { return temporary_path_.empty(); }

  // Flushes and closes, throws Error if any write failed, and renames into place.
  void commit();

 private:
  class Descriptor;  // a stream buffer over a file descriptor that keeps the first write error

  std::string path_;
  std::string target_path_;     // what commit() renames onto: path_ with its symlinks followed
  std::string temporary_path_;  // empty when writing in place
  std::unique_ptr<Descriptor> buffer_;
  std::ostream stream_;
  bool committed_ = false;
};

// Throws UsageError if `output` names the same regular file as one of `inputs`, also
// when one of them is reached through a symlink.
void refuse_overwriting_inputs(const std::string& output, const std::vector<std::string>& inputs);

// Throws UsageError if `folder` is empty or exists as anything but a directory (the
// folder outputs such as `report --out DIR`; the files in it go through AtomicFile).
void check_output_folder(const std::string& folder);

// A folder output (`report --out DIR`, `demo`) that appears whole or not at all. Its files
// are written into a staging folder beside DIR (.DIR.partial-XXXXXX, same file system);
// commit() renames that folder to DIR when DIR did not exist, or else writes each file
// into DIR under the rule above (replacing files of the same name, keeping the others).
// Without commit() — an error, an interrupt — the destructor removes the staging folder,
// so DIR is left as it was: not created, no new or half-written files in it. A process
// that ends without its destructors (a second Ctrl-C, a kill) leaves its staging folder;
// the next StagedFolder of DIR removes those of processes that no longer run.
class StagedFolder {
 public:
  // Throws UsageError as check_output_folder, Error if the staging folder cannot be made.
  explicit StagedFolder(std::string folder);
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;
  ~StagedFolder();

  const std::string& staging() const { return staging_; }  // where to write the files
  const std::string& folder() const { return folder_; }    // where they end up
  // Where `staged`, a path inside staging(), is after commit().
  std::string committed_path(const std::string& staged) const;
  void commit();

 private:
  std::string folder_;
  std::string staging_;
  bool committed_ = false;
};

// Writes `text` to `path` under the rule above.
void write_file_atomically(const std::string& path, const std::string& text,
                           const std::vector<std::string>& inputs = {});

}  // namespace thermodrift
