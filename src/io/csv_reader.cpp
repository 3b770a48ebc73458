#include "thermodrift/io/csv_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace {

constexpr std::size_t kDialectRows = 20;  // data rows looked at to learn the column count

std::string_view trim(std::string_view text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t");
  text = text.substr(first, last - first + 1);
  if (text.size() >= 2 && text.front() == '"' && text.back() == '"') {
    text = text.substr(1, text.size() - 2);
  }
  return text;
}

bool is_blank(std::string_view line) { return trim(line).empty(); }

// Comment and banner lines: '#' and '%' comments, '//' comments, and the '=~=~=' banner
// that PuTTY writes at the top of every log it saves.
bool is_comment(std::string_view line) {
  const auto text = trim(line);
  return text.starts_with('#') || text.starts_with('%') || text.starts_with("//") ||
         text.starts_with('=');
}

bool is_number(std::string_view cell) {
  double value = 0;
  const auto* end = cell.data() + cell.size();
  const auto result = std::from_chars(cell.data(), end, value);
  return !cell.empty() && result.ec == std::errc{} && result.ptr == end;
}

// The delimiter is the most frequent of comma, semicolon and tab on the first line that
// has any of them; 0 when it has none.
char guess_delimiter(std::string_view line) {
  char best = 0;
  std::ptrdiff_t best_count = 0;
  for (char candidate : {',', ';', '\t'}) {
    const auto count = std::count(line.begin(), line.end(), candidate);
    if (count > best_count) {
      best = candidate;
      best_count = count;
    }
  }
  return best;
}

}  // namespace

CellStatus parse_number(std::string_view cell, double& value) {
  if (cell.empty()) return CellStatus::empty;
  const char* begin = cell.data();
  if (cell.front() == '+') ++begin;  // from_chars does not take a leading '+'
  const auto* end = cell.data() + cell.size();
  const auto result = std::from_chars(begin, end, value);
  if (result.ec == std::errc::result_out_of_range) return CellStatus::out_of_range;
  if (result.ec != std::errc{} || result.ptr != end) return CellStatus::not_a_number;
  if (!std::isfinite(value)) return CellStatus::not_finite;
  return CellStatus::ok;
}

std::string describe(CellStatus status, std::string_view cell) {
  switch (status) {
    case CellStatus::ok: return "a number";
    case CellStatus::empty: return "empty cell, expected a number";
    case CellStatus::not_a_number: return fmt::format("'{}' is not a number", excerpt(cell));
    case CellStatus::not_finite: return fmt::format("'{}' is not a finite number", excerpt(cell));
    case CellStatus::out_of_range: return fmt::format("'{}' is out of the range of a double", excerpt(cell));
  }
  return "bad cell";
}

double parse_cell(std::string_view cell, const std::string& file, std::size_t line,
                  std::size_t column) {
  double value = 0;
  const auto status = parse_number(cell, value);
  if (status != CellStatus::ok) throw DataError(file, line, column, describe(status, cell));
  return value;
}

CsvReader::CsvReader(std::string path, CsvOptions options)
    : path_(std::move(path)), options_(options), stream_(std::make_unique<std::ifstream>(path_, std::ios::binary)) {
  if (!*stream_) throw DataError(path_, 0, 0, "cannot open the file for reading");
  learn_dialect();
}

CsvReader::CsvReader(std::unique_ptr<std::istream> input, std::string name, CsvOptions options)
    : path_(std::move(name)), options_(options), stream_(std::move(input)) {
  learn_dialect();
}

bool CsvReader::read_line(std::string& line) {
  line.clear();
  std::streambuf& input = *stream_->rdbuf();
  bool any = false;
  for (auto c = input.sbumpc(); c != std::char_traits<char>::eof(); c = input.sbumpc()) {
    any = true;
    if (c == '\n') break;
    // Said for what they are, not left to fail later as "no time column found".
    if (c == '\0' || (line_number_ == 0 && line.empty() && (c == 0xFF || c == 0xFE))) {
      throw DataError(path_, line_number_ + 1, line.size() + 1,
                      "a NUL byte or a UTF-16 byte-order mark: the file is UTF-16 or binary, not a text log "
                      "(save it as UTF-8)");
    }
    if (c == '\r' && input.sgetc() != '\n' && input.sgetc() != std::char_traits<char>::eof()) {
      throw DataError(path_, line_number_ + 1, line.size() + 1,
                      "a line ends in CR alone (old Mac OS line endings): convert the file to LF or CRLF");
    }
    if (line.size() == options_.max_line_bytes) {
      throw DataError(path_, line_number_ + 1, 0,
                      fmt::format("line longer than {} bytes (no line ending?): not a log line", options_.max_line_bytes));
    }
    line.push_back(static_cast<char>(c));
  }
  if (!any) return false;
  ++line_number_;
  if (line_number_ == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

CsvRow CsvReader::split(std::string line, std::size_t line_number) const {
  CsvRow row;
  row.line = line_number;
  row.text = std::move(line);
  const std::string_view text = row.text;
  std::size_t start = 0;
  while (true) {
    const auto cut = text.find(delimiter_, start);
    const auto cell = trim(text.substr(start, cut == std::string_view::npos ? cut : cut - start));
    row.spans.emplace_back(cell.empty() ? start : static_cast<std::size_t>(cell.data() - text.data()),
                           cell.size());
    if (cut == std::string_view::npos) break;
    start = cut + 1;
  }
  return row;
}

void CsvReader::learn_dialect() {
  std::string line;
  bool delimiter_known = false;
  while (lookahead_.size() < kDialectRows && read_line(line)) {
    if (is_blank(line)) continue;
    if (is_comment(line)) {
      ++skipped_comments_;
      continue;
    }
    if (!delimiter_known) {
      const char guess = guess_delimiter(line);
      if (guess == 0) {  // a banner line before the data: no delimiter at all
        ++skipped_comments_;
        continue;
      }
      delimiter_ = guess;
      delimiter_known = true;
    }
    auto row = split(line, line_number_);
    bool any_number = false;
    for (std::size_t i = 0; i < row.size(); ++i) any_number = any_number || is_number(row.cell(i));
    if (!any_number && lookahead_.empty() && header_.empty()) {
      for (std::size_t i = 0; i < row.size(); ++i) header_.emplace_back(row.cell(i));
      header_line_ = row.line;
      continue;
    }
    lookahead_.push_back(std::move(row));
  }

  if (!header_.empty()) {
    column_count_ = header_.size();
  } else {
    // The most common field count of the first rows: a garbled or cut-short row among
    // them must not set the shape of the whole log.
    std::size_t best_votes = 0;
    for (const auto& candidate : lookahead_) {
      const auto votes = static_cast<std::size_t>(std::count_if(
          lookahead_.begin(), lookahead_.end(), [&](const CsvRow& r) { return r.size() == candidate.size(); }));
      if (votes > best_votes || (votes == best_votes && candidate.size() > column_count_)) {
        best_votes = votes;
        column_count_ = candidate.size();
      }
    }
  }
  if (lookahead_.empty()) {
    throw DataError(path_, line_number_ == 0 ? 0 : line_number_, 0,
                    header_.empty() ? "no data rows in the file" : "only a header, no data rows");
  }
  std::reverse(lookahead_.begin(), lookahead_.end());  // pop from the back in file order
}

std::optional<CsvRow> CsvReader::next() {
  while (true) {
    std::optional<CsvRow> row;
    if (!lookahead_.empty()) {
      row = std::move(lookahead_.back());
      lookahead_.pop_back();
    } else {
      std::string line;
      do {
        if (!read_line(line)) return std::nullopt;
        if (is_comment(line)) {
          ++skipped_comments_;
          line.clear();
        }
      } while (is_blank(line));
      row = split(std::move(line), line_number_);
    }
    // A logger that ends every field with the delimiter leaves an empty field past the
    // header's last: not a field (a row with a value there is still one too many).
    if (row->size() == column_count_ + 1 && row->spans.back().second == 0) row->spans.pop_back();
    const std::size_t count = row->size();
    if (count == column_count_) {
      ++rows_returned_;
      return row;
    }
    if (count < column_count_) {
      // A terminal that started logging mid-line cuts the first row short, one that
      // stopped mid-line cuts the last: those rows are dropped, not fatal.
      const bool first_row = rows_returned_ == 0 && dropped_rows_.empty();
      bool last_row = false;
      if (!first_row && lookahead_.empty()) {
        const auto here = stream_->tellg();
        const auto line_here = line_number_;
        std::string peek;
        bool more = false;
        while (read_line(peek)) {
          if (!is_blank(peek) && !is_comment(peek)) {
            more = true;
            break;
          }
        }
        last_row = !more;
        stream_->clear();
        stream_->seekg(here);
        line_number_ = line_here;
      }
      if (first_row || last_row) {
        dropped_rows_.push_back(fmt::format("line {}: {} row cut short ({} of {} fields), dropped",
                                            row->line, first_row ? "first" : "last", count,
                                            column_count_));
        continue;
      }
      drop_garbled(*row, count + 1, fmt::format("row has {} fields, expected {}", count, column_count_));
      continue;
    }
    // Column of the first extra field: one past the expected count.
    drop_garbled(*row, column_count_ + 1, fmt::format("row has {} fields, expected {}", count, column_count_));
  }
}

void CsvReader::drop_garbled(const CsvRow& row, std::size_t column, const std::string& message) {
  if (options_.garbled_per_thousand == 0) throw DataError(path_, row.line, column, message);
  garbled_.push_back({row.line, column, message});
  if (rows_returned_ > 0) --rows_returned_;  // the row was counted when handed out
}

void CsvReader::finish() const {
  if (garbled_.empty()) return;
  if (garbled_.size() * 1000 > options_.garbled_per_thousand * rows_returned_) {
    const auto& first = garbled_.front();
    throw DataError(path_, first.line, first.column,
                    garbled_.size() == 1
                        ? first.message
                        : fmt::format("{} (and {} more malformed rows)", first.message, garbled_.size() - 1));
  }
}

std::vector<std::string> CsvReader::warnings() const {
  std::vector<std::string> out;
  if (skipped_comments_ > 0) {
    out.push_back(fmt::format("{}: skipped {} banner/comment line{}", path_, skipped_comments_,
                              skipped_comments_ == 1 ? "" : "s"));
  }
  for (const auto& dropped : dropped_rows_) out.push_back(fmt::format("{}: {}", path_, dropped));
  for (const auto& row : garbled_) {
    out.push_back(fmt::format("{}:{}:{}: {}; garbled row dropped", path_, row.line, row.column, row.message));
  }
  return out;
}

}  // namespace thermodrift
