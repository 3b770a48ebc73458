// Row-by-row reader of delimited text logs as serial terminals and data loggers write
// them: optional UTF-8 BOM, CRLF or LF, comma/semicolon/tab, banner and comment lines,
// an optional header row. Streaming, so a log larger than memory can be read.
#pragma once

#include <cstddef>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace thermodrift {

// One data row as it stands in the file.
struct CsvRow {
  std::size_t line = 0;  // 1-based line number in the file
  std::string text;      // the line without its line ending
  // Each cell as (offset, length) into `text`, trimmed of blanks and of one pair of
  // double quotes; offsets rather than views so that a row can be moved freely.
  std::vector<std::pair<std::size_t, std::size_t>> spans;

  std::size_t size() const { return spans.size(); }
  std::string_view cell(std::size_t index) const {
    return std::string_view(text).substr(spans[index].first, spans[index].second);
  }
};

// A serial link that drops or merges a byte now and then garbles a row: a field too
// many or too few, two numbers run together ("-0.3-0.31"). Such rows are dropped with a
// warning naming line and column while they stay rare (at most `garbled_per_thousand`
// per 1000 data rows, judged at finish()); past that, or with 0 (strict), the first one
// is the error. NaN/Inf, time going backwards and missing columns are always errors.
struct CsvOptions {
  std::size_t garbled_per_thousand = 1;  // tolerated garbled rows per 1000 data rows; 0: strict
  // A longer line is a DataError at its line, found while reading it: a log line is a
  // hundred bytes, and one without a line ending must not be held whole (docs/data.md).
  std::size_t max_line_bytes = std::size_t{1} << 20;
};

class CsvReader {
 public:
  // Opens `path` and reads up to the first data row to learn the dialect: delimiter,
  // header, number of columns. Throws DataError if the file cannot be read or holds no
  // data row.
  explicit CsvReader(std::string path, CsvOptions options = {});
  // The same over any seekable stream; `name` stands for the file in messages.
  CsvReader(std::unique_ptr<std::istream> input, std::string name, CsvOptions options = {});

  const std::string& path() const { return path_; }
  char delimiter() const { return delimiter_; }
  bool has_header() const { return !header_.empty(); }
  const std::vector<std::string>& header() const { return header_; }  // empty without one
  std::size_t column_count() const { return column_count_; }
  std::size_t header_line() const { return header_line_; }  // 0 without a header

  // The next data row, with exactly column_count() cells, or nothing at the end.
  // Comment and banner lines are skipped and counted; a row cut short as the first or
  // the last row of the file is dropped with a warning; any other row of the wrong
  // length is a DataError naming line and column.
  std::optional<CsvRow> next();

  // Drops `row` as garbled because of `column` (1-based); throws DataError instead when
  // strict. Callers use it for cells that are not numbers.
  void drop_garbled(const CsvRow& row, std::size_t column, const std::string& message);
  // Call after the last row: throws DataError naming the first garbled row when they
  // were more than the tolerated share.
  void finish() const;

  std::size_t skipped_comment_lines() const { return skipped_comments_; }
  std::size_t garbled_rows() const { return garbled_.size(); }
  // Human-readable warnings gathered so far (skipped lines, dropped cut-short rows).
  std::vector<std::string> warnings() const;

 private:
  bool read_line(std::string& line);
  void learn_dialect();
  CsvRow split(std::string line, std::size_t line_number) const;

  struct Garbled {
    std::size_t line;
    std::size_t column;
    std::string message;
  };

  std::string path_;
  CsvOptions options_;
  std::unique_ptr<std::istream> stream_;
  std::size_t line_number_ = 0;
  char delimiter_ = ',';
  std::vector<std::string> header_;
  std::size_t header_line_ = 0;
  std::size_t column_count_ = 0;
  std::vector<CsvRow> lookahead_;  // data rows read while learning the dialect
  std::size_t rows_returned_ = 0;
  std::size_t skipped_comments_ = 0;
  std::vector<std::string> dropped_rows_;
  std::vector<Garbled> garbled_;
};

// How a cell reads as a number.
enum class CellStatus { ok, empty, not_a_number, not_finite, out_of_range };
CellStatus parse_number(std::string_view cell, double& value);

// Parses one cell as a finite double. Throws DataError(file, line, column) naming the
// cell when it is empty, not a number, or NaN/Inf.
double parse_cell(std::string_view cell, const std::string& file, std::size_t line,
                  std::size_t column);

}  // namespace thermodrift
