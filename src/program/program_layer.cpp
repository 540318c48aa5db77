// ProgramLayer (program.hpp): one layer of a program as steps, as an engine builds it.
#include <cmath>
#include <cstdarg>

#include "nonplanar/program.hpp"
#include "program/gcode_text.hpp"

namespace nonplanar {

using StepKind = ProgramStep::Kind;

void ProgramLayer::clear() {
  steps.clear(), moves.clear(), text.clear();
  too_long = false;
}

void ProgramLayer::text_step(StepKind kind, std::string_view bytes, double value) {
  ProgramStep s;
  s.kind = kind;
  s.begin = static_cast<std::uint32_t>(text.size());
  text.append(bytes);
  s.end = static_cast<std::uint32_t>(text.size());
  s.value = value;
  steps.push_back(s);
}

void ProgramLayer::raw(std::string_view line) {
  text_step(StepKind::raw, line, 0);
  text.push_back('\n');
  steps.back().end = static_cast<std::uint32_t>(text.size());
}

void ProgramLayer::block(std::string_view lines) {
  if (!lines.empty()) text_step(StepKind::raw, lines, 0);
}

void ProgramLayer::line(const char* fmt, ...) {
  char buf[256];
  va_list ap;
  va_start(ap, fmt);
  too_long |= !program::format_line(buf, fmt, ap);
  va_end(ap);
  raw(buf);
}

std::size_t ProgramLayer::z_comment(double z) {
  steps.push_back(ProgramStep{StepKind::z_comment, 0, 0, z});
  return steps.size() - 1;
}

std::size_t ProgramLayer::height_comment(double h) {
  steps.push_back(ProgramStep{StepKind::height_comment, 0, 0, h});
  return steps.size() - 1;
}

void ProgramLayer::e_reset(std::string_view line, double e) {
  raw(line);
  steps.back().kind = StepKind::e_reset, steps.back().value = e;
}

void ProgramLayer::e_mode(std::string_view line, bool relative) {
  raw(line);
  steps.back().kind = StepKind::e_mode, steps.back().value = relative ? 1 : 0;
}

void ProgramLayer::start(StepKind kind, ExtrusionRole role, double width) {
  ProgramStep s;
  s.kind = kind;
  s.begin = s.end = static_cast<std::uint32_t>(moves.size());
  s.role = role, s.width = width;
  steps.push_back(s);
}

void ProgramLayer::move(const ProgramMove& m) {
  if (steps.empty() || !steps.back().moves()) start(StepKind::travel);
  moves.push_back(m);
  steps.back().end = static_cast<std::uint32_t>(moves.size());
}

void ProgramLayer::move_from(const Vec3& from, const Vec3& p, double de, double f, double height) {
  ProgramMove m;
  m.to = p, m.de = de, m.f = f, m.height = height;
  m.xy = std::abs(p.x() - from.x()) > 5e-4 || std::abs(p.y() - from.y()) > 5e-4;
  m.z = std::abs(p.z() - from.z()) > 5e-4;
  if (m.xy || m.z || !std::isnan(de) || !std::isnan(f)) move(m);
}

void ProgramLayer::lifted_travel(const Vec3& at, const Vec3& to, double lift, double f_first,
                                 double f_rest, double de) {
  start(StepKind::travel);
  const Vec3 up(at.x(), at.y(), lift), over(to.x(), to.y(), lift);
  move_from(at, up, kNoValue, f_first);
  move_from(up, over, kNoValue, f_rest);
  move_from(over, to, de, f_rest);
}

}  // namespace nonplanar
