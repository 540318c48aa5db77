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
