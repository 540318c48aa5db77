// The `=~ /regex/` of PrusaSlicer's placeholder language, matched in time linear in the
// text: a Thompson NFA run as a set of states (Pike's VM without captures). std::regex
// backtracks, so a profile's `/(a|a)*b/` took it exponential time and a long string
// overflowed its recursion (found by fuzz_macros).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace nonplanar::config {

/// What a regex may hold: the ECMAScript subset stock profiles use and a little more.
///   literals, `.`, `[abc]`, `[^a-z]`, `\d \w \s \D \W \S`, `\.` (any escaped punctuation),
///   `( )`, `(?: )`, `|` (empty alternatives too: `(|LP)`), `* + ?`, `{m}`, `{m,}`, `{m,n}`
///   (m, n ≤ 100), lazy forms (`*?`, same answer for a whole-string match), `^` and `$`.
/// Backreferences, lookarounds and named classes are refused.
struct RegexResult {
  bool matched = false;
  std::string error;  ///< empty when the regex compiled and ran; else why it did not
};

/// Whether all of `text` matches `re` (as std::regex_match). `budget` is the number of
/// state steps still allowed to this caller, decreased by what the match costs; when it runs
/// out the result is an error rather than a long wait.
RegexResult regex_full_match(std::string_view re, std::string_view text, std::size_t& budget);

}  // namespace nonplanar::config
