#include "thermodrift/error.hpp"

#include <fmt/format.h>

namespace thermodrift {

namespace {
std::string locate(const std::string& file, std::size_t line, std::size_t column,
                   const std::string& message) {
  if (line == 0) return fmt::format("{}: {}", file, message);
  if (column == 0) return fmt::format("{}:{}: {}", file, line, message);
  return fmt::format("{}:{}:{}: {}", file, line, column, message);
}
}  // namespace

std::string excerpt(std::string_view text, std::size_t limit) {
  if (text.size() <= limit) return std::string(text);
  std::size_t cut = limit;
  // Back off continuation bytes (10xxxxxx) so no character is split.
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  std::string out(text.substr(0, cut));  // appended, not operator+: GCC 12 warns falsely (-Wrestrict) on that
  out += "…";
  return out;
}

DataError::DataError(std::string file, std::size_t line, std::size_t column,
                     const std::string& message)
    : Error(locate(file, line, column, message)),
      file_(std::move(file)),
      line_(line),
      column_(column),
      message_(message) {}

}  // namespace thermodrift
