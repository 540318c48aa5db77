#include "program/gcode_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace nonplanar::program {
namespace {

// Appends " <letter><v>" with `digits` decimals, as printf's %.<digits>f writes it (to_chars
// with a precision is specified so), in a fraction of its time: printf was half of writing
// the bunny's 700 000 lines. False when it would not fit a line.
bool word(std::string& s, char letter, double v, int digits) {
  char buf[64];
  buf[0] = ' ', buf[1] = letter;
  const auto r = std::to_chars(buf + 2, buf + sizeof buf, v, std::chars_format::fixed, digits);
  if (r.ec != std::errc()) return false;
  s.append(buf, r.ptr);
  return true;
}

}  // namespace

void GcodeText::line(const char* fmt, ...) {
  char buf[256];
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if ((n < 0 || n >= static_cast<int>(sizeof buf)) && !fault)
    fault = Error{Status::internal_error, "a G-code line would not fit 255 characters"};
  raw(buf);
}

void GcodeText::move(const Vec3& p, const MoveWords& w) {
  std::string s = "G1";
  bool fits = true;
  if (w.xy) fits = word(s, 'X', p.x(), 3) && word(s, 'Y', p.y(), 3);
  if (w.z) fits = fits && word(s, 'Z', p.z(), 3);
  if (!std::isnan(w.de)) {
    e_ += w.de;
    fits = fits && word(s, 'E', rel_e_ ? w.de : e_, 5);
  }
  if (!std::isnan(w.f)) {
    char buf[32];
    const double f = std::round(w.f);
    fits = fits && std::abs(f) < 2e9;
    if (fits) std::snprintf(buf, sizeof buf, " F%d", static_cast<int>(f));
    if (fits) s += buf;
  }
  if (w.comment) s += std::string(" ; ") + w.comment;
  if ((!fits || s.size() > 255) && !fault)
    fault = Error{Status::internal_error, "a G-code line would not fit 255 characters"};
  raw(s);
}

void GcodeText::move_from(const Vec3& from, const Vec3& p, double de, double f) {
  MoveWords w;
  w.xy = std::abs(p.x() - from.x()) > 5e-4 || std::abs(p.y() - from.y()) > 5e-4;
  w.z = std::abs(p.z() - from.z()) > 5e-4;
  w.de = de, w.f = f;
  if (w.xy || w.z || !std::isnan(de) || !std::isnan(f)) move(p, w);
}

void lifted_travel(GcodeText& w, const Vec3& at, const Vec3& to, double lift, double f_first,
                   double f_rest, double de) {
  const Vec3 up(at.x(), at.y(), lift), over(to.x(), to.y(), lift);
  w.move_from(at, up, kNoValue, f_first);
  w.move_from(up, over, kNoValue, f_rest);
  w.move_from(over, to, de, f_rest);
}

}  // namespace nonplanar::program
