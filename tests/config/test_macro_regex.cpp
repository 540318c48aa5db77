// The =~ matcher (config/macro_regex.hpp): the same answers as std::regex_match on what
// profiles write, in linear time where std::regex backtracks, and clear errors.
#include <gtest/gtest.h>

#include <regex>
#include <string>
#include <vector>

#include "config/macro_regex.hpp"

namespace nonplanar::config {
namespace {

RegexResult match(const std::string& re, const std::string& text) {
  std::size_t budget = 10'000'000;
  return regex_full_match(re, text, budget);
}

TEST(MacroRegex, AgreesWithStdRegexOnProfilePatterns) {
  // The shapes of PrusaSlicer's stock bundles (grep '=~' profiles/*.ini) and the usual
  // syntax around them, each against texts that match and texts that do not.
  const std::vector<std::string> patterns = {
      ".*PRINTER_VENDOR_PRUSA3D.*",
      ".*PRINTER_MODEL_MK(2.5|3).*",
      "(ENDER|CR|SERMOON).*",
      ".*PRINTER_MODEL_AK(|LP).*",
      ".*PRINTER_MODEL_MK2[^\\.].*",
      ".*Prusament PA11.*",
      ".*GMAX2",
      "^MK[0-9]+S?$",
      "[a-c]{2,3}x?",
      "(?:ab|a)+b*?",
      "\\d+\\.\\d{1,2}",
      "\\w+\\s\\S*",
      "a{0}b",
      "(a|)*",
      "[^]a-c]*",
      ".*(MINI|MK4).*",
      "x{2,}",
      "[-a]+\\-",
  };
  const std::vector<std::string> texts = {
      "",
      "PRINTER_VENDOR_PRUSA3D\nPRINTER_MODEL_MK3\n",
      "PRINTER_VENDOR_PRUSA3D PRINTER_MODEL_MK3 ",
      "PRINTER_MODEL_MK2.5",
      "PRINTER_MODEL_MK2S",
      "ENDER3",
      "SERMOON D1",
      "PRINTER_MODEL_AKLP x",
      "PRINTER_MODEL_AK",
      "Prusament PA11 Carbon",
      "GMAX2",
      "MK3S",
      "MK",
      "abx",
      "abcc",
      "aab",
      "abab",
      "0.15",
      "12.345",
      "word rest",
      "b",
      "]]a",
      "MK4",
      "xxx",
      "x",
      "--a-",
  };
  int matched = 0;
  for (const auto& re : patterns)
    for (const auto& t : texts) {
      const RegexResult r = match(re, t);
      ASSERT_TRUE(r.error.empty()) << re << ": " << r.error;
      const bool want = std::regex_match(t, std::regex(re));
      EXPECT_EQ(r.matched, want) << "/" << re << "/ on '" << t << "'";
      matched += want;
    }
  EXPECT_GE(matched, 20);  // the table is not all misses (25 of 468 match)
}

TEST(MacroRegex, PathologicalPatternsTakeLinearTime) {
  // (a|a)*b backtracks 2^n ways in std::regex; (a*)* loops on empty steps.
  const std::string a40(40, 'a'), a10k(10000, 'a');
  EXPECT_FALSE(match("(a|a)*b", a40).matched);
  EXPECT_TRUE(match("(a|a)*b", a40 + "b").matched);
  EXPECT_TRUE(match("(a*)*", a10k).matched);
  EXPECT_FALSE(match("(a*)*b", a10k).matched);
  EXPECT_TRUE(match("(.*)*a.{20}", std::string(100, 'a')).matched);
  // A budget that cannot cover the work is an error, and is spent, not reset.
  std::size_t budget = 1000;
  const RegexResult r = regex_full_match("(a|a)*b", a10k, budget);
  EXPECT_EQ(r.error, "=~: /regex/ too costly for its text");
  EXPECT_EQ(budget, 0u);
}

TEST(MacroRegex, WhatItCannotReadIsAnError) {
  EXPECT_EQ(match("(ab", "ab").error, "missing ')'");
  EXPECT_EQ(match("ab)", "ab").error, "unmatched ')'");
  EXPECT_EQ(match("[ab", "ab").error, "missing ']'");
  EXPECT_EQ(match("*a", "a").error, "nothing to repeat");
  EXPECT_EQ(match("a**", "a").error, "nothing to repeat");
  EXPECT_EQ(match("(a)\\1", "aa").error, "\\1 is not supported");
  EXPECT_EQ(match("(?=a)a", "a").error, "lookarounds and named groups are not supported");
  EXPECT_EQ(match("[z-a]", "a").error, "a range out of order in [...]");
  EXPECT_EQ(match("a{3,1}", "a").error, "{m,n} with n < m");
  EXPECT_EQ(match("a{101}", "a").error, "a count over 100 in {m,n}");
  EXPECT_EQ(match("(((a{100}){100}){100})", "a").error,
            "/regex/ too large once its counts are expanded");
  EXPECT_EQ(match(std::string(200, '(') + std::string(200, ')'), "").error,
            "groups nested too deeply");
  EXPECT_TRUE(match("a{,2}", "a{,2}").matched);  // not a count: a literal '{', as ECMAScript
}

}  // namespace
}  // namespace nonplanar::config
