// The parsers' number reading (core/text_tokens.hpp): the plain-decimal fast path must give the
// very double from_chars gives (the G-code reader's figures agree with check's to the digit).
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <random>
#include <string>

#include "core/text_tokens.hpp"

namespace {

using nonplanar::core::parse_double;

double reference(const std::string& t) {
  const std::string s = !t.empty() && t[0] == '+' ? t.substr(1) : t;
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  EXPECT_EQ(ec, std::errc()) << t;
  EXPECT_EQ(end, s.data() + s.size()) << t;
  return v;
}

// Random decimals of 1 to 19 digits, the point anywhere (or none), either sign: G-code's
// numbers and far more digits than any slicer writes, past 2^53 where the fast path must step
// aside.
TEST(TextTokens, PlainDecimalsReadAsFromCharsReadsThem) {
  std::mt19937_64 rng(7);
  for (int n = 0; n < 200000; ++n) {
    const int digits = 1 + static_cast<int>(rng() % 19);
    std::string t = rng() % 3 == 0 ? "-" : rng() % 5 == 0 ? "+" : "";
    const int point = static_cast<int>(rng() % (digits + 1));  // == digits: no point
    for (int d = 0; d < digits; ++d) {
      if (d == point && d > 0) t += '.';
      t += static_cast<char>('0' + rng() % 10);
    }
    const auto v = parse_double(t);
    ASSERT_TRUE(v.has_value()) << t;
    const double r = reference(t);
    ASSERT_EQ(std::signbit(*v), std::signbit(r)) << t;
    ASSERT_EQ(*v, r) << t;
  }
}

TEST(TextTokens, OtherNumbersAndGarbage) {
  EXPECT_EQ(*parse_double("100.123"), 100.123);
  EXPECT_EQ(*parse_double("-0.0321"), -0.0321);
  EXPECT_TRUE(std::signbit(*parse_double("-0")));
  EXPECT_EQ(*parse_double("1e3"), 1000.0);
  EXPECT_EQ(*parse_double("1."), 1.0);
  EXPECT_EQ(*parse_double(".5"), 0.5);
  EXPECT_EQ(*parse_double("9007199254740993.5"), reference("9007199254740993.5"));
  EXPECT_EQ(*parse_double("0.1234567890123456789012"), reference("0.1234567890123456789012"));
  for (const char* bad : {"", "-", "+", ".", "1.2.3", "1x", "x1", "nan", "inf", "1e999", "- 1"})
    EXPECT_FALSE(parse_double(bad).has_value()) << bad;
}

}  // namespace
