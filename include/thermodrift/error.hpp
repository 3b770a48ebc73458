// Typed errors of the library. The library throws; only the CLI turns an error into
// one line on stderr and an exit status (CLI.md: 2 usage, 3 bad input data, 1 other).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace thermodrift {

// Base of every error the library throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The caller asked for something impossible (bad option value, unknown column name).
class UsageError : public Error {
 public:
  using Error::Error;
};

// The user or a callback asked to stop (Ctrl-C). Outputs in progress are discarded.
class Interrupted : public Error {
 public:
  using Error::Error;
};

// The input data (a log, a libsvm file, a model file) is malformed. Carries where:
// `line` and `column` are 1-based, 0 when they do not apply. what() is the whole
// one-line message, "FILE:LINE:COLUMN: what was wrong".
class DataError : public Error {
 public:
  DataError(std::string file, std::size_t line, std::size_t column, const std::string& message);

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  std::size_t column() const { return column_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  std::size_t line_;
  std::size_t column_;
  std::string message_;
};

// At most `limit` characters of `text` (a cell, a header name) for a message, then "…":
// a 50 MB cell must not be echoed whole. Cut at a UTF-8 character boundary.
std::string excerpt(std::string_view text, std::size_t limit = 40);

// Exit statuses of the command-line tool (CLI.md).
enum class ExitStatus : int { ok = 0, failure = 1, usage = 2, bad_data = 3, interrupted = 130 };

}  // namespace thermodrift
