// Text helpers shared by every parser (meshes, profiles, surfaces, G-code): a line-aware
// tokenizer and strict number parsing. Parsers take the bytes in memory so they can be fuzzed.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/status.hpp"

namespace nonplanar::core {

/// Parse a whole token as a finite double ("1e3", "-0.5"); nullopt for anything else,
/// including "nan", "inf" and trailing garbage.
std::optional<double> parse_double(std::string_view token);
/// Parse a whole token as a long long; nullopt on garbage or overflow.
std::optional<long long> parse_int(std::string_view token);

/// Splits text into whitespace-separated tokens and counts lines (LF, CRLF and lone CR).
class Tokenizer {
 public:
  explicit Tokenizer(std::string_view text) : text_(text) {}
  /// Next token, or empty at the end. line() is the line of the returned token.
  std::string_view next();
  /// Skip to the start of the next line.
  void skip_line();
  /// The rest of the current line (without the line break), consuming it.
  std::string_view rest_of_line();
  bool at_end();
  int line() const { return line_; }

 private:
  void skip_space();
  std::string_view text_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

/// PrusaSlicer's escapes in an .ini value undone (\\n, \\t, \\r; a backslash before any other
/// character keeps that character).
std::string unescape_ini(std::string_view v);
/// A per-extruder string list as PrusaSlicer writes it ("\"a\";\"b\""), each item unescaped.
/// A value that does not start with a quote is one string.
std::vector<std::string> ini_string_list(std::string_view v);

/// "line N: msg" — the parsers' error text, to be prefixed by the file name by the loader.
Error parse_error_at(int line, const std::string& msg);

}  // namespace nonplanar::core
