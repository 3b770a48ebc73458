// Where a JSON text's values stand: each value's first character by its JSON pointer, the
// nearest enclosing value for a pointer the text lacks.
#include "thermodrift/io/json_position.hpp"

#include <gtest/gtest.h>

namespace thermodrift {
namespace {

TEST(JsonPositions, EveryValueByItsPointer) {
  const std::string text =
      "{\n"
      "  \"a\": [1, {\"b\": \"x,]}\\\"\"},\n"  // a string holding delimiters and an escaped quote
      "   null],\n"
      "  \"c/d\": {\"e~f\": true}, \"g\": -1.5e3\n"
      "}\n";
  const JsonPositions positions(text);
  EXPECT_EQ(positions.of(""), TextPosition(1, 1));
  EXPECT_EQ(positions.of("/a"), TextPosition(2, 8));
  EXPECT_EQ(positions.of("/a/0"), TextPosition(2, 9));
  EXPECT_EQ(positions.of("/a/1"), TextPosition(2, 12));
  EXPECT_EQ(positions.of("/a/1/b"), TextPosition(2, 18));
  EXPECT_EQ(positions.of("/a/2"), TextPosition(3, 4));
  EXPECT_EQ(positions.of(json_pointer_child("", "c/d")), TextPosition(4, 10));
  EXPECT_EQ(positions.of(json_pointer_child(json_pointer_child("", "c/d"), "e~f")), TextPosition(4, 18));
  EXPECT_EQ(positions.of("/g"), TextPosition(4, 30));
  // Not in the text: the value that would hold it.
  EXPECT_EQ(positions.of("/a/1/missing"), TextPosition(2, 12));
  EXPECT_EQ(positions.of("/nothing/at/all"), TextPosition(1, 1));
  EXPECT_EQ(positions.of("no slash"), TextPosition(1, 1));  // not a pointer: the whole text
}

TEST(JsonPositions, AByteOrderMarkIsNoColumn) {
  EXPECT_EQ(JsonPositions("\xEF\xBB\xBF{\"k\": 2}").of("/k"), TextPosition(1, 7));
}

}  // namespace
}  // namespace thermodrift
