// The pbrt-v4 tokenizer (scene/pbrt_tokenizer.h).
#include "scene/pbrt_tokenizer.h"

#include <fmt/format.h>

#include "util/error.h"

namespace raysort {

void PbrtTokenizer::fail(std::size_t line, const std::string& why) const {
  throw Error(fmt::format("pbrt-v4 file {}:{}: {}; fix the file (docs/scene-format.md, \"pbrt-v4\")", origin_, line, why));
}

PbrtToken PbrtTokenizer::peek() {
  if (!peeked_) {
    ahead_ = scan();
    peeked_ = true;
  }
  return ahead_;
}

PbrtToken PbrtTokenizer::next() {
  PbrtToken t = peek();
  peeked_ = false;
  return t;
}

PbrtToken PbrtTokenizer::scan() {
  auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; };
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') ++line_;
    if (is_space(c)) {
      ++pos_;
    } else if (c == '#') {
      while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    } else {
      break;
    }
  }
  PbrtToken t;
  t.line = line_;
  if (pos_ >= text_.size()) return t;
  const char c = text_[pos_];
  if (c == '[' || c == ']') {
    t.kind = c == '[' ? PbrtToken::Open : PbrtToken::Close;
    t.text = text_.substr(pos_++, 1);
    return t;
  }
  if (c == '"') {
    const std::size_t start = ++pos_;
    while (pos_ < text_.size() && text_[pos_] != '"') {
      if (text_[pos_] == '\n') fail(t.line, "a string is not closed before the end of its line (a missing '\"')");
      // An escaped character (\" or \\) stays in the string; a backslash does not carry a string over a
      // line end (found by fuzz/pbrt_fuzzer: a string with a newline made a two-line error).
      const bool escape = text_[pos_] == '\\' && pos_ + 1 < text_.size() && text_[pos_ + 1] != '\n';
      pos_ += escape ? 2 : 1;
    }
    if (pos_ >= text_.size()) fail(t.line, "a string is not closed before the end of the file (a missing '\"')");
    t.kind = PbrtToken::String;
    t.text = text_.substr(start, pos_++ - start);
    return t;
  }
  const std::size_t start = pos_;
  while (pos_ < text_.size() && !is_space(text_[pos_]) && text_[pos_] != '"' && text_[pos_] != '[' &&
         text_[pos_] != ']' && text_[pos_] != '#')
    ++pos_;
  t.text = text_.substr(start, pos_ - start);
  const char f = t.text[0];
  t.kind = (f >= '0' && f <= '9') || f == '-' || f == '+' || f == '.' ? PbrtToken::Number : PbrtToken::Word;
  return t;
}

}  // namespace raysort
