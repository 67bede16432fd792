#pragma once
// The tokens of a pbrt-v4 scene file (pbrt-v4's file format, "Scene Description" §1): quoted
// strings, numbers, [ and ], and bare words (directives, true/false); # starts a comment to the
// end of the line. Each token knows its line, for the one-line errors of the loader.
#include <cstddef>
#include <string>
#include <string_view>

namespace raysort {

struct PbrtToken {
  enum Kind { End, Word, String, Number, Open, Close } kind = End;
  std::string_view text;  // a string without its quotes
  std::size_t line = 0;
};

class PbrtTokenizer {
 public:
  PbrtTokenizer(std::string_view text, const std::string& origin) : text_(text), origin_(origin) {}
  PbrtToken next();
  PbrtToken peek();
  // Throws Error "pbrt-v4 file ORIGIN:LINE: WHY; fix the file".
  [[noreturn]] void fail(std::size_t line, const std::string& why) const;
  const std::string& origin() const { return origin_; }

 private:
  PbrtToken scan();
  std::string_view text_;
  std::size_t pos_ = 0, line_ = 1;
  const std::string& origin_;
  bool peeked_ = false;
  PbrtToken ahead_;
};

}  // namespace raysort
