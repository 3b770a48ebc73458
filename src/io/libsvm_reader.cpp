#include "thermodrift/io/libsvm_reader.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "thermodrift/error.hpp"

namespace thermodrift {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// A whole token as a finite double; false if any character is left over.
bool parse_double(std::string_view token, double* value) {
  if (token.empty()) return false;
  std::string text(token);
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && errno != ERANGE && std::isfinite(*value);
}

// A whole token as a positive integer index.
bool parse_index(std::string_view token, long* index) {
  if (token.empty() || token.size() > 9) return false;
  long parsed = 0;
  for (char c : token) {
    if (c < '0' || c > '9') return false;
    parsed = parsed * 10 + (c - '0');
  }
  *index = parsed;
  return parsed >= 1;
}

// std::getline up to kMaxLibsvmLineBytes: a file without line endings (a binary file, a
// 50 MB line) is refused having read just over the limit, not held whole.
bool read_line(std::istream& input, std::string& line, std::size_t line_number, const std::string& name) {
  line.clear();
  std::streambuf& buffer = *input.rdbuf();
  bool any = false;
  for (auto c = buffer.sbumpc(); c != std::char_traits<char>::eof(); c = buffer.sbumpc()) {
    any = true;
    if (c == '\n') break;
    if (line.size() == kMaxLibsvmLineBytes) {
      throw DataError(name, line_number, 0,
                      fmt::format("line longer than {} bytes (no line ending?): not a libsvm line", kMaxLibsvmLineBytes));
    }
    line.push_back(static_cast<char>(c));
  }
  return any;
}

struct SparseRow {
  double label = 0;
  std::vector<std::pair<long, double>> entries;  // (1-based index, value)
};

}  // namespace

LabelledData read_libsvm(std::istream& input, const std::string& name, const StopToken& stop) {
  std::vector<SparseRow> rows;
  long max_index = 0;
  std::string line;
  std::size_t line_number = 0;
  while (read_line(input, line, line_number + 1, name)) {
    ++line_number;
    if (line_number % 4096 == 0) stop.throw_if_requested("reading the libsvm file");
    std::string_view text(line);
    std::size_t position = 0;
    auto next_token = [&]() -> std::pair<std::size_t, std::string_view> {
      while (position < text.size() && is_blank(text[position])) ++position;
      std::size_t start = position;
      while (position < text.size() && !is_blank(text[position])) ++position;
      return {start, text.substr(start, position - start)};
    };
    auto [label_start, label_token] = next_token();
    if (label_token.empty()) continue;  // a blank line
    SparseRow row;
    if (!parse_double(label_token, &row.label)) {
      throw DataError(name, line_number, label_start + 1,
                      fmt::format("bad label '{}': expected a finite number", excerpt(label_token)));
    }
    long previous_index = 0;
    for (;;) {
      auto [start, token] = next_token();
      if (token.empty()) break;
      std::size_t colon = token.find(':');
      if (colon == std::string_view::npos) {
        throw DataError(name, line_number, start + 1,
                        fmt::format("missing ':' in '{}': expected index:value", excerpt(token)));
      }
      long index = 0;
      if (!parse_index(token.substr(0, colon), &index)) {
        throw DataError(name, line_number, start + 1,
                        fmt::format("bad index '{}': expected an integer >= 1",
                                    excerpt(token.substr(0, colon))));
      }
      if (index <= previous_index) {
        throw DataError(name, line_number, start + 1,
                        fmt::format("index {} is not greater than the previous index {}", index,
                                    previous_index));
      }
      double value = 0;
      if (!parse_double(token.substr(colon + 1), &value)) {
        throw DataError(name, line_number, start + colon + 2,
                        fmt::format("bad value '{}': expected a finite number",
                                    excerpt(token.substr(colon + 1))));
      }
      if (index > kMaxLibsvmFeatureIndex) {
        throw DataError(name, line_number, start + 1,
                        fmt::format("feature index {} is above the supported {} (data are held dense)",
                                    index, kMaxLibsvmFeatureIndex));
      }
      previous_index = index;
      if (index > max_index) max_index = index;
      row.entries.emplace_back(index, value);
    }
    if (static_cast<long long>(rows.size() + 1) * max_index > kMaxLibsvmDenseCells) {
      throw DataError(name, line_number, 1,
                      fmt::format("{} rows x {} features exceed the supported {} dense values",
                                  rows.size() + 1, max_index, kMaxLibsvmDenseCells));
    }
    rows.push_back(std::move(row));
  }
  if (input.bad()) throw DataError(name, 0, 0, "read error");
  if (rows.empty()) throw DataError(name, 0, 0, "no data lines (empty libsvm file)");

  LabelledData data;
  data.samples = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), max_index);
  data.targets.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto row_index = static_cast<Eigen::Index>(r);
    data.targets(row_index) = rows[r].label;
    for (const auto& [index, value] : rows[r].entries) data.samples(row_index, index - 1) = value;
  }
  return data;
}

LabelledData read_libsvm(const std::string& path, const StopToken& stop) {
  std::ifstream input(path);
  if (!input) throw DataError(path, 0, 0, "cannot open file");
  return read_libsvm(input, path, stop);
}

void write_libsvm(std::ostream& output, const Eigen::MatrixXd& samples,
                  const Eigen::VectorXd& targets) {
  for (Eigen::Index row = 0; row < samples.rows(); ++row) {
    std::string line = fmt::format("{:.17g}", targets(row));
    for (Eigen::Index column = 0; column < samples.cols(); ++column) {
      line += fmt::format(" {}:{:.17g}", column + 1, samples(row, column));
    }
    line += '\n';
    output << line;
  }
}

}  // namespace thermodrift
