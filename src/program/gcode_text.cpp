#include "program/gcode_text.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace nonplanar::program {
namespace {

// Appends one formatted word; false when it would not fit a line.
bool word(std::string& s, const char* fmt, double v) {
  char buf[64];
  const int n = std::snprintf(buf, sizeof buf, fmt, v);
  if (n < 0 || n >= static_cast<int>(sizeof buf)) return false;
  s += buf;
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
  if (w.xy) fits = word(s, " X%.3f", p.x()) && word(s, " Y%.3f", p.y());
  if (w.z) fits = fits && word(s, " Z%.3f", p.z());
  if (!std::isnan(w.de)) {
    e_ += w.de;
    fits = fits && word(s, " E%.5f", rel_e_ ? w.de : e_);
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
