// LineSplicer (splice_lines.hpp): kept lines of a file, with what the dropped ones had set.
#include "program/splice_lines.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace nonplanar::program {

namespace {

constexpr double kSameE = 1e-6;    ///< mm of filament
constexpr double kSameAt = 1e-4;   ///< mm: the file writes 3 decimals
constexpr double kSameFeed = 0.5;  ///< mm/min
constexpr double kHopOver = 2.0;   ///< mm: a travel it adds longer than this is retracted around
constexpr double kTravelF = 7800;  ///< mm/min: its travels' feed rate (PrusaSlicer's default)

bool fan_line(std::string_view raw) {
  return raw.rfind("M106", 0) == 0 || raw.rfind("M107", 0) == 0;
}

}  // namespace

LineSplicer::LineSplicer(const GcodeProgram& prog) : prog_(prog) {
  if (prog.retraction.f > 0) retract_f_ = prog.retraction.f;  // (false for kNoValue, a NaN)
}

void LineSplicer::follow(const GcodeLine& l, State& s) const {
  using Kind = GcodeLine::Kind;
  switch (l.kind) {
    case Kind::move: {
      const GcodeMove& m = prog_.moves[static_cast<std::size_t>(l.move)];
      if (m.has_e && !s.relative_e) s.e += m.de;
      if (m.has_e && !m.extruding()) s.retracted -= m.de;
      // Only the axes it writes (an F-only line leaves the text's head where it was).
      if (m.has_xy) s.at.head<2>() = m.to.head<2>();
      if (m.has_z) s.at.z() = m.to.z();
      s.feed = m.feed;
      return;
    }
    case Kind::e_reset:
      s.e = l.value;
      return;
    case Kind::e_mode:
      s.relative_e = l.value != 0;
      return;
    case Kind::xyz_relative:
      s.relative_e = true;
      return;
    case Kind::text:
      if (fan_line(l.raw)) s.fan = l.raw;
      return;
    default:
      return;
  }
}

void LineSplicer::add(std::string& out, std::vector<char>* marks, const char* fmt, ...) {
  char buf[160];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  out.append(buf).push_back('\n');
  if (marks) marks->push_back(0);
}

void LineSplicer::reconcile(const GcodeMove& m, std::string& out, std::vector<char>* marks) {
  State& t = text_state_;
  if (t.relative_e != file_.relative_e) {
    add(out, marks, "%s", file_.relative_e ? "M83" : "M82");
    t.relative_e = file_.relative_e;
  }
  // Filament to push (negative: to pull back) so the text is retracted as the file is.
  // A travel pulls back what the file has pulled back; the give-back waits for an E move.
  double push = t.retracted - file_.retracted;
  if (std::abs(push) <= kSameE || !(m.has_e || (m.has_xy && push < 0))) push = 0;
  if (m.has_e || push != 0) {
    if (!file_.relative_e && (push != 0 || std::abs(t.e - file_.e) > kSameE))
      add(out, marks, "G92 E%.5f", file_.e - push);
    t.e = file_.e - push;
  }
  auto move_e = [&] {
    if (file_.relative_e)
      add(out, marks, "G1 E%.5f F%.0f", push, retract_f_);
    else
      add(out, marks, "G1 E%.5f F%.0f", file_.e, retract_f_);
    t.e = file_.e, t.retracted = file_.retracted, t.feed = retract_f_;
  };
  if (push < 0) move_e();  // pulled back before the travel
  const Vec3& from = m.from;
  const double travel = (t.at.head<2>() - from.head<2>()).norm();
  if (m.extruding() && travel > kSameAt) {
    // Pulled back around it as the file's own travels are (the dropped lines held them).
    const double len = prog_.retraction.length;
    const bool hop = push == 0 && len > 0 && travel > kHopOver;
    if (hop) {
      add(out, marks, "G1 E%.5f F%.0f", t.relative_e ? -len : t.e - len, retract_f_);
      if (!t.relative_e) t.e -= len;
    }
    add(out, marks, "G1 X%.3f Y%.3f Z%.3f F%.0f", from.x(), from.y(), from.z(), kTravelF);
    t.at = from, t.feed = kTravelF;
    if (hop) {
      const double back = prog_.retraction.back_f > 0 ? prog_.retraction.back_f : retract_f_;
      add(out, marks, "G1 E%.5f F%.0f", t.relative_e ? len : t.e + len, back);
      if (!t.relative_e) t.e += len;
      t.feed = back;
    }
  } else if (m.has_xy && !m.has_z && std::abs(t.at.z() - from.z()) > kSameAt) {
    add(out, marks, "G1 Z%.3f", from.z());
    t.at.z() = from.z();
  }
  if (push > 0) move_e();  // given back where the file's extrusion begins
  if (std::isnan(m.f) && !std::isnan(m.feed) &&
      (std::isnan(t.feed) || std::abs(t.feed - m.feed) > kSameFeed)) {
    add(out, marks, "G1 F%.0f", m.feed);
    t.feed = m.feed;
  }
  if (m.extruding() && t.fan != file_.fan) {
    add(out, marks, "%.*s", static_cast<int>(file_.fan.empty() ? 4 : file_.fan.size()),
        file_.fan.empty() ? "M107" : file_.fan.data());
    t.fan = file_.fan;
  }
}

void LineSplicer::append(std::size_t begin, std::size_t end, const std::vector<char>& keep,
                         std::string& out, std::vector<char>* marks) {
  for (; next_ < begin && next_ < prog_.lines.size(); ++next_) follow(prog_.lines[next_], file_);
  for (std::size_t i = std::max(begin, next_); i < end && i < prog_.lines.size(); ++i) {
    const GcodeLine& l = prog_.lines[i];
    if (l.kind == GcodeLine::Kind::xyz_relative && prog_.in_print(i) && problem_.empty())
      problem_ = "line " + std::to_string(i + 1) +
                 ": relative moves (G91), under which the moves added between kept lines "
                 "would go astray";
    const GcodeMove* m =
        l.kind == GcodeLine::Kind::move ? &prog_.moves[static_cast<std::size_t>(l.move)] : nullptr;
    if (keep[i] && m && m->wipe && m->has_xy &&
        (text_state_.at.head<2>() - m->from.head<2>()).norm() > kSameAt) {
      // A wipe retraces the extrusion before it, which this text does not have: its filament
      // is pulled back where the head is.
      GcodeMove in_place = *m;
      in_place.has_xy = in_place.wipe = false, in_place.f = retract_f_;
      reconcile(in_place, out, marks);
      State& t = text_state_;
      if (!t.relative_e) t.e += m->de;
      t.retracted -= m->de, t.feed = retract_f_;
      add(out, marks, "G1 E%.5f F%.0f", t.relative_e ? m->de : t.e, retract_f_);
    } else if (keep[i]) {
      if (m) reconcile(*m, out, marks);
      out.append(l.raw).push_back('\n');
      if (marks) marks->push_back(keep[i]);
      follow(l, text_state_);
    }
    follow(l, file_);
    next_ = i + 1;
  }
}

}  // namespace nonplanar::program
