// Where the values of a JSON text stand in it, so that a file read as JSON and refused
// for what a value means (not for its syntax) can still be named FILE:LINE:COLUMN.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace thermodrift {

// A 1-based line and column; {0, 0} where nothing is known.
using TextPosition = std::pair<std::size_t, std::size_t>;

class JsonPositions {
 public:
  // `text` must be valid JSON (parsed before; it recurses once per level of nesting, which
  // the caller bounds); each value's first character is indexed by its JSON pointer
  // (RFC 6901: "/axes/0/pipeline"; "" the whole text).
  explicit JsonPositions(std::string_view text);

  // Where `pointer` starts, or its nearest enclosing value the text has.
  TextPosition of(std::string_view pointer) const;

 private:
  std::unordered_map<std::string, TextPosition> positions_;
};

// The line and column of the character at `index` in `text` (the end, if beyond it).
TextPosition text_position(std::string_view text, std::size_t index);

// A member's JSON pointer below `parent`: "/" then the key with ~ and / escaped.
std::string json_pointer_child(std::string_view parent, std::string_view key);

}  // namespace thermodrift
