// Small helpers shared by the tests: a temporary directory removed at scope end, writing
// and reading whole files, and running a shell command with its exit status, stdout and
// stderr captured.
#pragma once

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace thermodrift::testing {

class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "thermodrift-test-XXXXXX").string();
    std::vector<char> buffer(pattern.begin(), pattern.end());
    buffer.push_back('\0');
    if (mkdtemp(buffer.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = buffer.data();
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }

  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

  // Writes `text` to `name` inside the directory and returns its full path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::string full = file(name);
    std::ofstream out(full, std::ios::binary);
    out << text;
    if (!out) throw std::runtime_error("cannot write " + full);
    return full;
  }

  // Names of the entries in the directory, sorted.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(path_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  std::filesystem::path path_;
};

// Whether `text` holds `part`.
inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Lines of `text` without their line endings; a last line without '\n' counts.
inline std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// The comma-separated cells of one CSV line (no quoting), and back.
inline std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream row(line);
  for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}
inline std::string join_cells(const std::vector<std::string>& cells) {
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
  return line;
}

struct CommandResult {
  int status = -1;  // exit status, or -1 when the command did not exit normally
  std::string out;
  std::string err;
};

// Runs `command` through /bin/sh in `dir`, capturing stdout and stderr into files there
// (named so that they are easy to tell apart from the command's own outputs).
inline CommandResult run_in(const TempDir& dir, const std::string& command) {
  const std::string out_path = dir.file(".stdout.capture");
  const std::string err_path = dir.file(".stderr.capture");
  const std::string full = "cd '" + dir.path().string() + "' && " + command + " > '" + out_path +
                           "' 2> '" + err_path + "'";
  const int raw = std::system(full.c_str());
  CommandResult result;
  result.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
  result.out = read_file(out_path);
  result.err = read_file(err_path);
  std::filesystem::remove(out_path);
  std::filesystem::remove(err_path);
  return result;
}

#ifdef THERMODRIFT_BINARY
// The thermodrift binary under test.
inline const std::string kBinary = THERMODRIFT_BINARY;

// Runs the thermodrift binary under test with `arguments` in `dir`.
inline CommandResult run_thermodrift(const TempDir& dir, const std::string& arguments) {
  return run_in(dir, "'" + kBinary + "' " + arguments);
}
#endif

// The column options of a simulated chamber log (`thermodrift simulate`): its three
// thermometers, and its three gyro axes with them.
inline const std::string kTemps = " --temp temp_x,temp_y,temp_z";
inline const std::string kColumns = " --gyro gyro_x,gyro_y,gyro_z --temp temp_x,temp_y,temp_z";

}  // namespace thermodrift::testing
