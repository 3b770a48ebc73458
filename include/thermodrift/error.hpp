// Typed errors of the library, compiled in src/core (thermodrift_core, which every module
// links). The library throws; only the CLI turns an error into one line on stderr and an
// exit status (apps/thermodrift/exit_status.hpp).
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

// How an options struct's IsValid(std::string* why) says no, the same everywhere:
//   const Invalid fail(why, "afsa");
//   if (fish < 1) return fail(fmt::format("fish must be >= 1, got {}", fish));
// sets *why (when given) to "afsa: fish must be >= 1, got 0" and returns false.
class Invalid {
 public:
  explicit Invalid(std::string* why, std::string_view context = {}) : why_(why), context_(context) {}
  bool operator()(const std::string& reason) const {
    if (why_ != nullptr) *why_ = context_.empty() ? reason : std::string(context_) + ": " + reason;
    return false;
  }

 private:
  std::string* why_;
  std::string_view context_;
};

}  // namespace thermodrift
