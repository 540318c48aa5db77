#include "program/gcode_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>

namespace nonplanar::program {
namespace {

// |v| with `digits` (at most 6) decimals into p, as the integer nearest a = |v|·10^digits,
// when a is below 10^9 and not exactly halfway: the product is rounded once, and rounding is
// monotonic, so it never crosses a halfway point, which is a double there; the nearest integer
// to a is then the one to the exact product, the correctly rounded decimal printf writes.
// Returns the end, or null (halfway, large or non-finite: to_chars decides).
char* fixed_fast(char* p, double v, int digits) {
  static constexpr double kScale[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6};
  static constexpr std::uint64_t kPow[] = {1, 10, 100, 1000, 10000, 100000, 1000000};
  const double a = std::fabs(v) * kScale[digits];
  if (!(a < 1e9)) return nullptr;
  const double whole = std::floor(a), frac = a - whole;
  if (frac == 0.5) return nullptr;
  const auto n = static_cast<std::uint64_t>(whole) + (frac > 0.5);
  auto r = std::to_chars(p, p + 24, n / kPow[digits]);
  p = r.ptr;
  if (digits == 0) return p;
  *p++ = '.';
  std::uint64_t f = n % kPow[digits];
  for (int d = digits - 1; d >= 0; --d) p[d] = static_cast<char>('0' + f % 10), f /= 10;
  return p + digits;
}

// Appends " <letter><v>" with `digits` decimals, as printf's %.<digits>f writes it (a sign for
// any negative value, "-0.000" too): by integers where that is exact (fixed_fast: a million
// moves in 161 ms against 290, BM_WriteMoves1M), else by to_chars with a precision, which is
// specified so and was a fraction of printf's time (half of writing the bunny's 700 000
// lines). False when it would not fit a line.
bool word(std::string& s, char letter, double v, int digits) {
  char buf[64];
  buf[0] = ' ', buf[1] = letter;
  char* p = buf + 2;
  if (std::signbit(v) && std::isfinite(v)) *p++ = '-';
  if (char* end = digits <= 6 ? fixed_fast(p, v, digits) : nullptr) {
    s.append(buf, end);
    return true;
  }
  const auto r = std::to_chars(buf + 2, buf + sizeof buf, v, std::chars_format::fixed, digits);
  if (r.ec != std::errc()) return false;
  s.append(buf, r.ptr);
  return true;
}

}  // namespace

bool format_line(char (&buf)[256], const char* fmt, va_list ap) {
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  return n >= 0 && n < static_cast<int>(sizeof buf);
}

Error line_too_long() {
  return Error{Status::internal_error, "a G-code line would not fit 255 characters"};
}

void GcodeText::line(const char* fmt, ...) {
  char buf[256];
  va_list ap;
  va_start(ap, fmt);
  const bool fits = format_line(buf, fmt, ap);
  va_end(ap);
  if (!fits && !fault) fault = line_too_long();
  raw(buf);
}

// Straight into `out`: a line in a string of its own was an allocation a move (longer than
// the string's inline room), 700 000 of them for the bunny.
void GcodeText::move(const ProgramMove& m) {
  const std::size_t start = out.size();
  out += "G1";
  bool fits = true;
  if (m.xy) fits = word(out, 'X', m.to.x(), 3) && word(out, 'Y', m.to.y(), 3);
  if (m.z) fits = fits && word(out, 'Z', m.to.z(), 3);
  if (!std::isnan(m.de)) {
    e_ += m.de;
    fits = fits && word(out, 'E', rel_e_ ? m.de : e_, 5);
  }
  if (!std::isnan(m.f)) {
    char buf[32];
    const double f = std::round(m.f);
    fits = fits && std::abs(f) < 2e9;
    if (fits) std::snprintf(buf, sizeof buf, " F%d", static_cast<int>(f));
    if (fits) out += buf;
  }
  if (m.comment) out.append(" ; ").append(m.comment);
  if ((!fits || out.size() - start > 255) && !fault) fault = line_too_long();
  out.push_back('\n');
}

void write_program_layer(GcodeText& w, const ProgramLayer& layer) {
  using StepKind = ProgramStep::Kind;
  if (layer.too_long && !w.fault) w.fault = line_too_long();
  for (const ProgramStep& s : layer.steps) {
    const std::string_view bytes =
        s.moves() ? std::string_view()
                  : std::string_view(layer.text).substr(s.begin, s.end - s.begin);
    switch (s.kind) {
      case StepKind::raw:
        w.block(bytes);
        break;
      case StepKind::z_comment:
        w.line(";Z:%.3f", s.value);
        break;
      case StepKind::height_comment:
        w.line(";HEIGHT:%.3f", s.value);
        break;
      case StepKind::e_reset:
        w.block(bytes), w.set_e(s.value);
        break;
      case StepKind::e_mode:
        w.block(bytes), w.set_relative(s.value != 0);
        break;
      case StepKind::travel:
      case StepKind::extrusion:
      case StepKind::retract:
        for (std::uint32_t k = s.begin; k < s.end; ++k) w.move(layer.moves[k]);
        break;
    }
  }
}

}  // namespace nonplanar::program
