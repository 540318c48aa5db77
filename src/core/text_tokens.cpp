#include "core/text_tokens.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>

namespace nonplanar::core {

namespace {
// A plain decimal ("-12.345", at most 19 digits, no exponent) as the integer of its digits
// over a power of ten: both exact in a double when the integer is at most 2^53 and the power
// at most 10^22, so the one division rounds correctly (Clinger's fast path), the very double
// from_chars gives. G-code's numbers are all such: so read, and its lines counted by memchr,
// the G-code reader's streaming pass over 27 MB took 71 ms against 92 (BM_ForEachPrintMove10MB).
// Anything else: nullopt, for from_chars to read.
std::optional<double> plain_decimal(std::string_view t) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  std::size_t i = 0;
  const bool neg = t[0] == '-';
  if (neg || t[0] == '+') ++i;
  std::uint64_t w = 0;
  int digits = 0, after_point = -1;  // after_point: digits after the point, -1 before it
  for (; i < t.size(); ++i) {
    const char c = t[i];
    if (c >= '0' && c <= '9') {
      if (++digits > 19) return std::nullopt;
      w = w * 10 + static_cast<std::uint64_t>(c - '0');
      if (after_point >= 0) ++after_point;
    } else if (c == '.' && after_point < 0 && digits > 0) {
      after_point = 0;
    } else {
      return std::nullopt;
    }
  }
  if (digits == 0 || after_point == 0 || w > (std::uint64_t{1} << 53)) return std::nullopt;
  const double v = static_cast<double>(w) / kPow10[after_point < 0 ? 0 : after_point];
  return neg ? -v : v;
}
}  // namespace

std::optional<double> parse_double(std::string_view t) {
  if (t.empty()) return std::nullopt;
  if (auto v = plain_decimal(t)) return v;
  if (t.front() == '+') t.remove_prefix(1);  // from_chars rejects a leading '+'
  double v = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<long long> parse_int(std::string_view t) {
  if (t.empty()) return std::nullopt;
  if (t.front() == '+') t.remove_prefix(1);
  long long v = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || end != t.data() + t.size()) return std::nullopt;
  return v;
}

void Tokenizer::skip_space() {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
    } else if (c == '\r') {
      if (pos_ + 1 >= text_.size() || text_[pos_ + 1] != '\n') ++line_;  // lone CR
    } else if (c != ' ' && c != '\t' && c != '\f' && c != '\v') {
      break;
    }
    ++pos_;
  }
}

std::string_view Tokenizer::next() {
  skip_space();
  const std::size_t start = pos_;
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') break;
    ++pos_;
  }
  return text_.substr(start, pos_ - start);
}

std::string_view Tokenizer::rest_of_line() {
  const std::size_t start = pos_;
  while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') ++pos_;
  return text_.substr(start, pos_ - start);
}

void Tokenizer::skip_line() {
  rest_of_line();
  if (pos_ < text_.size()) {
    if (text_[pos_] == '\r' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '\n') ++pos_;
    ++pos_;
    ++line_;
  }
}

bool Tokenizer::at_end() {
  skip_space();
  return pos_ >= text_.size();
}

Error parse_error_at(int line, const std::string& msg) {
  return Error{Status::parse_error, "line " + std::to_string(line) + ": " + msg};
}

std::string unescape_ini(std::string_view v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i] == '\\' && i + 1 < v.size()) {
      const char n = v[++i];
      out += n == 'n' ? '\n' : n == 't' ? '\t' : n == 'r' ? '\r' : n;
    } else {
      out += v[i];
    }
  }
  return out;
}

std::vector<std::string> ini_string_list(std::string_view v) {
  if (v.empty() || v.front() != '"') return {unescape_ini(v)};
  std::vector<std::string> items;
  std::size_t p = 0;
  while (p < v.size() && v[p] == '"') {
    std::string item;  // the quoted text, escapes intact until unescape_ini
    for (++p; p < v.size() && v[p] != '"'; ++p) {
      if (v[p] == '\\' && p + 1 < v.size()) item += v[p++];
      item += v[p];
    }
    items.push_back(unescape_ini(item));
    p = v.find('"', p + 1);
    if (p == std::string_view::npos) break;
  }
  return items;
}

}  // namespace nonplanar::core
