// The CSV dialect of chamber logs: BOM, CRLF, delimiters, banner lines, header or not,
// cut-short first and last rows, and the shape errors with their line and column.
#include "thermodrift/io/csv_reader.hpp"

#include <gtest/gtest.h>

#include <istream>
#include <memory>
#include <streambuf>
#include <string>
#include <vector>

#include "../../support/temp_dir.hpp"
#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

using testing::TempDir;

// Every data row of `reader`, as text cells.
std::vector<std::vector<std::string>> all_rows(CsvReader& reader) {
  std::vector<std::vector<std::string>> rows;
  while (auto row = reader.next()) {
    std::vector<std::string> cells;
    for (std::size_t i = 0; i < row->size(); ++i) cells.emplace_back(row->cell(i));
    rows.push_back(cells);
  }
  return rows;
}

// The DataError that reading all of `path` (rows and finish) throws; fails the test if none.
DataError read_error(const std::string& path, CsvOptions options = {}) {
  try {
    CsvReader reader(path, options);
    while (reader.next()) {
    }
    reader.finish();
  } catch (const DataError& error) {
    return error;
  }
  ADD_FAILURE() << "no DataError reading " << path;
  return DataError("", 0, 0, "");
}

using testing::contains;

TEST(CsvReader, HeaderRowIsRecognisedAndNotData) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time_s,gyro_x,temp\n0,1.5,20\n1,2.5,21\n");
  CsvReader reader(path);
  EXPECT_TRUE(reader.has_header());
  EXPECT_EQ(reader.header_line(), 1u);
  EXPECT_EQ(reader.header(), (std::vector<std::string>{"time_s", "gyro_x", "temp"}));
  EXPECT_EQ(reader.column_count(), 3u);
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"0", "1.5", "20"}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"1", "2.5", "21"}));
  EXPECT_TRUE(reader.warnings().empty());
}

TEST(CsvReader, WithoutHeaderTheFirstRowIsData) {
  TempDir dir;
  const auto path = dir.write("log.csv", "0,1.5,20\n1,2.5,21\n");
  CsvReader reader(path);
  EXPECT_FALSE(reader.has_header());
  EXPECT_EQ(reader.header_line(), 0u);
  EXPECT_EQ(reader.column_count(), 3u);
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0][1], "1.5");
}

TEST(CsvReader, RowsCarryTheirFileLineNumbers) {
  TempDir dir;
  const auto path = dir.write("log.csv", "# comment\ntime,g\n\n0,1\n# mid comment\n1,2\n");
  CsvReader reader(path);
  auto first = reader.next();
  auto second = reader.next();
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->line, 4u);
  EXPECT_EQ(second->line, 6u);
  EXPECT_FALSE(reader.next());
  EXPECT_EQ(reader.skipped_comment_lines(), 2u);
}

TEST(CsvReader, Utf8BomIsIgnored) {
  TempDir dir;
  const auto path = dir.write("log.csv", "\xEF\xBB\xBFtime,gyro\n0,1\n");
  CsvReader reader(path);
  ASSERT_TRUE(reader.has_header());
  EXPECT_EQ(reader.header().front(), "time");
  EXPECT_EQ(all_rows(reader).size(), 1u);
}

TEST(CsvReader, BomBeforeNumericFirstRow) {
  TempDir dir;
  const auto path = dir.write("log.csv", "\xEF\xBB\xBF" "0,1\n1,2\n");
  CsvReader reader(path);
  EXPECT_FALSE(reader.has_header());
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0][0], "0");
}

TEST(CsvReader, CrlfLineEndingsAreStripped) {
  TempDir dir;
  const auto path = dir.write("log.csv", "time,gyro\r\n0,1.25\r\n1,2.5\r\n");
  CsvReader reader(path);
  EXPECT_EQ(reader.header().back(), "gyro");
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0][1], "1.25");
  EXPECT_EQ(rows[1][1], "2.5");
}

TEST(CsvReader, DelimiterCommaSemicolonTab) {
  TempDir dir;
  struct Case {
    char delimiter;
    std::string text;
  };
  for (const Case& c : {Case{',', "t,a,b\n0,1,2\n"}, Case{';', "t;a;b\n0;1;2\n"}, Case{'\t', "t\ta\tb\n0\t1\t2\n"}}) {
    const auto path = dir.write("log.csv", c.text);
    CsvReader reader(path);
    EXPECT_EQ(reader.delimiter(), c.delimiter);
    EXPECT_EQ(reader.column_count(), 3u);
    const auto rows = all_rows(reader);
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0], (std::vector<std::string>{"0", "1", "2"}));
  }
}

TEST(CsvReader, CellsAreTrimmedAndUnquoted) {
  TempDir dir;
  const auto path = dir.write("log.csv", "\"time\" , \"gyro\"\n 0 ,\"1.5\"\n");
  CsvReader reader(path);
  EXPECT_EQ(reader.header(), (std::vector<std::string>{"time", "gyro"}));
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"0", "1.5"}));
}

TEST(CsvReader, BannerLinesAreSkippedWithACountingWarning) {
  TempDir dir;
  const auto path = dir.write("log.csv",
                              "=~=~=~= PuTTY log 2026.05.08 15:02:51 =~=~=~=\n"
                              "Logging started\n"
                              "# a comment\n"
                              "0,1\n1,2\n");
  CsvReader reader(path);
  EXPECT_EQ(all_rows(reader).size(), 2u);
  EXPECT_EQ(reader.skipped_comment_lines(), 3u);
  const auto warnings = reader.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "skipped 3 banner/comment lines")) << warnings[0];
  EXPECT_TRUE(contains(warnings[0], path)) << warnings[0];
}

TEST(CsvReader, CutShortFirstRowIsDroppedWithAWarning) {
  TempDir dir;
  const auto path = dir.write("log.csv", "=~= banner =~=\n3,4\n0,1,2\n1,2,3\n2,3,4\n");
  CsvReader reader(path);
  EXPECT_EQ(reader.column_count(), 3u);
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0][0], "0");
  reader.finish();
  const auto warnings = reader.warnings();
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_TRUE(contains(warnings[1], "line 2: first row cut short (2 of 3 fields), dropped")) << warnings[1];
}

TEST(CsvReader, CutShortLastRowIsDroppedWithAWarning) {
  TempDir dir;
  const auto path = dir.write("log.csv", "t,a,b\n0,1,2\n1,2,3\n2,3,4\n3,4");  // no final newline
  CsvReader reader(path);
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows.back()[0], "2");
  reader.finish();
  const auto warnings = reader.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "line 5: last row cut short (2 of 3 fields), dropped")) << warnings[0];
}

// The same past the rows read ahead to learn the dialect, followed by blank and comment lines.
TEST(CsvReader, CutShortLastRowOfALongLogIsDropped) {
  TempDir dir;
  std::string text = "t,a,b\n";
  for (int i = 0; i < 100; ++i) text += std::to_string(i) + ",1,2\n";
  text += "100,1\n\n# end of log\n";
  const auto path = dir.write("log.csv", text);
  CsvReader reader(path);
  EXPECT_EQ(all_rows(reader).size(), 100u);
  reader.finish();
  bool found = false;
  for (const auto& warning : reader.warnings()) found = found || contains(warning, "line 102: last row cut short");
  EXPECT_TRUE(found);
}

TEST(CsvReader, EmptyFileIsAnError) {
  TempDir dir;
  const auto error = read_error(dir.write("empty.csv", ""));
  EXPECT_EQ(error.line(), 0u);
  EXPECT_EQ(error.column(), 0u);
  EXPECT_TRUE(contains(error.message(), "no data rows")) << error.what();
  EXPECT_TRUE(contains(error.what(), "empty.csv")) << error.what();
}

TEST(CsvReader, OnlyBlankAndCommentLinesIsAnError) {
  TempDir dir;
  const auto error = read_error(dir.write("blank.csv", "\n# nothing\n\n"));
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 0u);
  EXPECT_TRUE(contains(error.message(), "no data rows")) << error.what();
}

TEST(CsvReader, OnlyAHeaderIsAnError) {
  TempDir dir;
  const auto error = read_error(dir.write("header.csv", "time,gyro,temp\n"));
  EXPECT_EQ(error.line(), 1u);
  EXPECT_EQ(error.column(), 0u);
  EXPECT_TRUE(contains(error.message(), "only a header")) << error.what();
  EXPECT_TRUE(contains(error.what(), "header.csv:1: ")) << error.what();
}

TEST(CsvReader, ShortRowInsideTheDataNamesLineAndFirstMissingColumn) {
  TempDir dir;
  const auto path = dir.write("short.csv", "t,a,b\n0,1,2\n1,2\n2,3,4\n3,4,5\n");
  const auto error = read_error(path);
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 3u);
  EXPECT_TRUE(contains(error.message(), "row has 2 fields, expected 3")) << error.what();
  EXPECT_TRUE(contains(error.what(), "short.csv:3:3: ")) << error.what();
}

TEST(CsvReader, LongRowNamesLineAndFirstExtraColumn) {
  TempDir dir;
  const auto path = dir.write("long.csv", "t,a,b\n0,1,2\n1,2,3,9\n2,3,4\n");
  const auto error = read_error(path);
  EXPECT_EQ(error.line(), 3u);
  EXPECT_EQ(error.column(), 4u);
  EXPECT_TRUE(contains(error.message(), "row has 4 fields, expected 3")) << error.what();
}

// A trailing delimiter on every data row (not on the header) is an empty field past the
// last column: read as the header's fields, in strict mode too; a value there is not.
TEST(CsvReader, ATrailingDelimiterOnTheDataRowsIsNotAField) {
  TempDir dir;
  CsvOptions strict;
  strict.garbled_per_thousand = 0;
  CsvReader reader(dir.write("trailing.csv", "t,a,b\n0,1,2,\n1,2,3 ,\n"), strict);
  const auto rows = all_rows(reader);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"0", "1", "2"}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"1", "2", "3"}));
  const auto error = read_error(dir.write("extra.csv", "t,a,b\n0,1,2,\n1,2,3,4\n"), strict);
  EXPECT_EQ(error.line(), 3u);
  EXPECT_TRUE(contains(error.message(), "row has 4 fields, expected 3")) << error.what();
}

TEST(CsvReader, StrictModeFailsAtTheRowItself) {
  TempDir dir;
  std::string text = "t,a,b\n";
  for (int i = 0; i < 3000; ++i) text += std::to_string(i) + (i == 1500 ? ",1\n" : ",1,2\n");
  const auto path = dir.write("strict.csv", text);
  CsvReader reader(path, CsvOptions{.garbled_per_thousand = 0});
  std::size_t rows = 0;
  try {
    while (reader.next()) ++rows;
    FAIL() << "strict reader accepted a short row";
  } catch (const DataError& error) {
    EXPECT_EQ(error.line(), 1502u);
    EXPECT_EQ(error.column(), 3u);
  }
  EXPECT_EQ(rows, 1500u);  // thrown when the row is met, not at finish()
}

TEST(CsvReader, RareGarbledRowInALongLogIsDroppedWithItsLineAndColumn) {
  TempDir dir;
  std::string text = "t,a,b\n";
  for (int i = 0; i < 2000; ++i) text += std::to_string(i) + (i == 1000 ? ",1,2,3\n" : ",1,2\n");
  const auto path = dir.write("rare.csv", text);
  CsvReader reader(path);
  std::vector<std::size_t> lines;
  while (auto row = reader.next()) lines.push_back(row->line);
  EXPECT_NO_THROW(reader.finish());
  ASSERT_EQ(lines.size(), 1999u);
  EXPECT_EQ(reader.garbled_rows(), 1u);
  // Line 1002 holds the garbled row; its neighbours survive.
  EXPECT_EQ(lines[999], 1001u);
  EXPECT_EQ(lines[1000], 1003u);
  bool warned = false;
  for (const auto& warning : reader.warnings()) {
    warned = warned || contains(warning, "rare.csv:1002:4: row has 4 fields, expected 3; garbled row dropped");
  }
  EXPECT_TRUE(warned);
}

TEST(CsvReader, TwoGarbledRowsInAThousandAreTooMany) {
  TempDir dir;
  std::string text = "t,a,b\n";
  for (int i = 0; i < 1000; ++i) text += std::to_string(i) + (i == 300 || i == 600 ? ",1\n" : ",1,2\n");
  const auto error = read_error(dir.write("many.csv", text));
  EXPECT_EQ(error.line(), 302u);  // the first one
  EXPECT_EQ(error.column(), 3u);
  EXPECT_TRUE(contains(error.message(), "and 1 more malformed rows")) << error.what();
}

// A log of `head`, then one line of `length` digits generated as read (never held), then
// `tail`; counts the bytes handed out.
class LongLineLog : public std::streambuf {
 public:
  LongLineLog(std::string head, std::size_t length, std::string tail)
      : head_(std::move(head)), length_(length), tail_(std::move(tail)) {}
  std::size_t handed_out() const { return handed_out_; }

 protected:
  int_type underflow() override {
    if (part_ == 0) {
      part_ = 1;
      return serve(head_.data(), head_.size());
    }
    if (part_ == 1 && left_of_line_ > 0) {
      const std::size_t n = std::min(left_of_line_, digits_.size());
      left_of_line_ -= n;
      return serve(digits_.data(), n);
    }
    if (part_ == 1) {
      part_ = 2;
      return serve(tail_.data(), tail_.size());
    }
    return traits_type::eof();
  }

 private:
  int_type serve(const char* data, std::size_t n) {
    if (n == 0) return underflow();
    char* begin = const_cast<char*>(data);
    setg(begin, begin, begin + n);
    handed_out_ += n;
    return traits_type::to_int_type(*begin);
  }
  std::string head_;
  std::size_t length_;
  std::string tail_;
  std::string digits_ = std::string(4096, '7');
  std::size_t left_of_line_ = length_;
  int part_ = 0;
  std::size_t handed_out_ = 0;
};

class StreamOf : public std::istream {
 public:
  explicit StreamOf(LongLineLog* log) : std::istream(log) {}
};

// A 50 MB line (a log written without line endings, a binary file) is refused at its line
// once the limit is passed, having read little more than the limit: memory per line is bounded.
TEST(CsvReader, ALineLongerThanTheLimitIsAnErrorFoundWhileReadingIt) {
  for (const std::string head : {std::string("time_s,temp,gyro_x\n0,20,1\n1,20,1\n"), std::string()}) {
    LongLineLog log(head, 50'000'000, "\n2,20,1\n");
    try {
      CsvReader reader(std::make_unique<StreamOf>(&log), "long.csv");
      while (reader.next()) {
      }
      ADD_FAILURE() << "a 50 MB line was read";
    } catch (const DataError& error) {
      EXPECT_EQ(error.line(), head.empty() ? 1u : 4u);
      EXPECT_TRUE(contains(error.message(), "line longer than 1048576 bytes")) << error.what();
      EXPECT_LT(error.message().size(), 100u);
    }
    EXPECT_LT(log.handed_out(), (1u << 20) + 8192u);
  }
  // Up to the limit a line is read.
  CsvOptions small;
  small.max_line_bytes = 12;
  TempDir dir;
  CsvReader up_to_the_limit(dir.write("ok.csv", "time_s,temp\n0,1234567890\n"), small);
  EXPECT_EQ(all_rows(up_to_the_limit).size(), 1u);
  const auto error = read_error(dir.write("long.csv", "time_s,temp\n0,12345678901\n"), small);
  EXPECT_EQ(error.line(), 2u);
}

// Messages quote at most 40 characters of a cell, cut at a character boundary.
TEST(CsvReader, MessagesQuoteAShortExcerptOfACell) {
  const std::string cell(5000, 'x');
  try {
    parse_cell(cell, "log.csv", 3, 2);
    ADD_FAILURE() << "accepted";
  } catch (const DataError& error) {
    EXPECT_EQ(error.message(), "'" + std::string(40, 'x') + "…' is not a number");
  }
  EXPECT_EQ(excerpt("short"), "short");
  std::string accented = "a";
  for (int i = 0; i < 30; ++i) accented += "é";  // two bytes each: byte 40 is a continuation
  EXPECT_EQ(excerpt(accented), accented.substr(0, 39) + "…");
}

TEST(ParseNumber, ClassifiesCells) {
  double value = 0;
  EXPECT_EQ(parse_number("1.5e3", value), CellStatus::ok);
  EXPECT_EQ(value, 1500.0);
  EXPECT_EQ(parse_number("+2", value), CellStatus::ok);
  EXPECT_EQ(value, 2.0);
  EXPECT_EQ(parse_number("", value), CellStatus::empty);
  EXPECT_EQ(parse_number("abc", value), CellStatus::not_a_number);
  EXPECT_EQ(parse_number("-0.3-0.31", value), CellStatus::not_a_number);
  EXPECT_EQ(parse_number("1,5", value), CellStatus::not_a_number);
  EXPECT_EQ(parse_number("nan", value), CellStatus::not_finite);
  EXPECT_EQ(parse_number("NaN", value), CellStatus::not_finite);
  EXPECT_EQ(parse_number("inf", value), CellStatus::not_finite);
  EXPECT_EQ(parse_number("-Infinity", value), CellStatus::not_finite);
  EXPECT_EQ(parse_number("1e999", value), CellStatus::out_of_range);
}

TEST(ParseCell, ErrorNamesFileLineAndColumn) {
  try {
    parse_cell("abc", "f.csv", 12, 4);
    FAIL();
  } catch (const DataError& error) {
    EXPECT_EQ(error.file(), "f.csv");
    EXPECT_EQ(error.line(), 12u);
    EXPECT_EQ(error.column(), 4u);
    EXPECT_EQ(std::string(error.what()), "f.csv:12:4: 'abc' is not a number");
  }
}

}  // namespace
}  // namespace thermodrift
