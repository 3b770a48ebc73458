#include "thermodrift/io/json_position.hpp"

namespace thermodrift {

namespace {

class Scanner {
 public:
  Scanner(std::string_view text, std::unordered_map<std::string, TextPosition>& out) : text_(text), out_(out) {}

  void value(const std::string& pointer) {
    skip_space();
    if (at_end()) return;
    out_.emplace(pointer, TextPosition{line_, column_});
    const char c = text_[i_];
    if (c == '{') {
      advance();
      while (skip_space(), !at_end() && text_[i_] != '}') {
        const std::string key = string();
        skip_space();
        advance();  // ':'
        value(json_pointer_child(pointer, key));
        skip_space();
        if (!at_end() && text_[i_] == ',') advance();
      }
      advance();
    } else if (c == '[') {
      advance();
      for (std::size_t index = 0; skip_space(), !at_end() && text_[i_] != ']'; ++index) {
        value(pointer + "/" + std::to_string(index));
        skip_space();
        if (!at_end() && text_[i_] == ',') advance();
      }
      advance();
    } else if (c == '"') {
      string();
    } else {
      while (!at_end() && std::string_view(",]} \t\r\n").find(text_[i_]) == std::string_view::npos) advance();
    }
  }

 private:
  bool at_end() const { return i_ >= text_.size(); }

  void advance() {
    if (at_end()) return;
    if (text_[i_] == '\n') {
      ++line_;
      column_ = 1;
    } else {
      ++column_;
    }
    ++i_;
  }

  void skip_space() {
    while (!at_end() && std::string_view(" \t\r\n").find(text_[i_]) != std::string_view::npos) advance();
  }

  // A string at its opening quote, as written: escapes are kept (a key that needs one is
  // looked up under its escaped form, and so falls back to its object).
  std::string string() {
    std::string out;
    advance();
    while (!at_end() && text_[i_] != '"') {
      if (text_[i_] == '\\') {
        out += text_[i_];
        advance();
        if (at_end()) break;
      }
      out += text_[i_];
      advance();
    }
    advance();
    return out;
  }

  std::string_view text_;
  std::unordered_map<std::string, TextPosition>& out_;
  std::size_t i_ = 0, line_ = 1, column_ = 1;
};

}  // namespace

TextPosition text_position(std::string_view text, std::size_t index) {
  TextPosition at{1, 1};
  for (std::size_t i = 0; i < index && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++at.first;
      at.second = 1;
    } else {
      ++at.second;
    }
  }
  return at;
}

std::string json_pointer_child(std::string_view parent, std::string_view key) {
  std::string out(parent);
  out += '/';
  for (const char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

JsonPositions::JsonPositions(std::string_view text) {
  // A UTF-8 byte-order mark, which the parser skips, is no column of the text.
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  Scanner(text, positions_).value("");
}

TextPosition JsonPositions::of(std::string_view pointer) const {
  while (true) {
    if (const auto found = positions_.find(std::string(pointer)); found != positions_.end()) return found->second;
    if (pointer.empty()) return {0, 0};
    const auto slash = pointer.rfind('/');
    pointer = slash == std::string_view::npos ? std::string_view() : pointer.substr(0, slash);
  }
}

}  // namespace thermodrift
