// The time estimate of print_time.hpp: PrusaSlicer's GCodeProcessor planner (itself Marlin's
// planner: classic jerk, or Marlin 2's junction deviation), with its queue of blocks.
// Notation: v speeds (mm/s), a acceleration (mm/s²), d a block's length (mm); axes X Y Z E;
// δ the junction deviation (mm), θ the angle between two moves' directions.
#include "nonplanar/print_time.hpp"
#include "core/huge_pages.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/text_tokens.hpp"

namespace nonplanar {
namespace {

using Axes = std::array<double, 4>;  // X, Y, Z, E

struct Block {
  double d = 0, a = 0;
  double cruise = 0, entry = 0, max_entry = 0, safe = 0;
  bool nominal_length = false;
  std::size_t line = 0;  ///< the line it is written on
  double time(double exit) const;
};

// Speed reachable from `v` over `d` at deceleration `a` (< 0 accelerates backwards).
double max_allowable(double a, double v, double d) {
  return std::sqrt(std::max(0.0, v * v - 2 * a * d));
}

// Marlin's trapezoid: accelerate from entry to cruise (or as far as the length allows),
// cruise, decelerate to exit.
double Block::time(double exit) const {
  if (d <= 0) return 0;
  if (a <= 0) return d / std::max(cruise, 1e-6);
  const double v0 = std::min(entry, cruise), v1 = std::min(exit, cruise);
  double acc = (cruise * cruise - v0 * v0) / (2 * a);
  const double dec = (cruise * cruise - v1 * v1) / (2 * a);
  double top = cruise, flat = d - acc - dec;
  if (flat < 0) {  // no cruise: the accelerating and decelerating ramps meet
    acc = std::clamp((2 * a * d - v0 * v0 + v1 * v1) / (4 * a), 0.0, d);
    top = std::sqrt(std::max(0.0, v0 * v0 + 2 * a * acc));
    flat = 0;
  }
  top = std::max(top, 1e-6);
  return (top - v0) / a + flat / top + (top - v1) / a;
}

// The limits as the program changes them: "M203 X200 Y200 Z12 E120" and the like.
class Limits {
 public:
  explicit Limits(const MachineLimits& m)
      : feed_{m.feed_x, m.feed_y, m.feed_z, m.feed_e},
        accel_{m.accel_x, m.accel_y, m.accel_z, m.accel_e},
        jerk_{m.jerk_x, m.jerk_y, m.jerk_z, m.jerk_e},
        deviation_(m.junction_deviation),
        max_print_(m.accel_extruding),
        max_travel_(m.accel_travel),
        print_(m.accel_extruding),
        retract_(m.accel_retracting),
        travel_(m.accel_travel),
        min_extruding_(m.min_extruding_rate),
        min_travel_(m.min_travel_rate) {}

  /// Reads an M201/M203/M204/M205 line; other lines change nothing.
  void read(std::string_view raw) {
    core::Tokenizer tok(raw.substr(0, raw.find(';')));
    const auto cmd = tok.next();
    if (cmd != "M201" && cmd != "M203" && cmd != "M204" && cmd != "M205") return;
    for (auto w = tok.next(); !w.empty(); w = tok.next()) {
      const auto v = core::parse_double(w.substr(1));
      if (!v || !std::isfinite(*v) || *v < 0) continue;
      const char k = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
      const int axis = k == 'X' ? 0 : k == 'Y' ? 1 : k == 'Z' ? 2 : k == 'E' ? 3 : -1;
      if (cmd == "M201" && axis >= 0) accel_[axis] = *v;
      if (cmd == "M203" && axis >= 0) feed_[axis] = *v;
      if (cmd == "M205" && axis >= 0) jerk_[axis] = *v;
      if (cmd == "M205" && k == 'J') deviation_ = *v;  // Marlin 2 (PrusaSlicer's viewer skips it)
      if (cmd == "M204") {  // capped by the profile's limits, as PrusaSlicer caps them
        auto cap = [](double x, double max) { return max > 0 ? std::min(x, max) : x; };
        if (k == 'S' || k == 'P') print_ = cap(*v, max_print_);
        if (k == 'S' || k == 'T') travel_ = cap(*v, max_travel_);
        if (k == 'R') retract_ = *v;
      }
    }
  }
  Axes feed_, accel_, jerk_;
  double deviation_;
  double max_print_, max_travel_, print_, retract_, travel_, min_extruding_, min_travel_;
};

// What the planner remembers of the last block for the next junction.
struct Previous {
  double feed = 0, safe = 0;
  Axes axis{0, 0, 0, 0};  // signed axis speeds
  Axes unit{0, 0, 0, 0};  // its XYZE per mm of its length (junction deviation's direction)
};

// Classic jerk: the highest speed at which no axis changes speed by more than its jerk
// across the junction (PrusaSlicer's process_G1, Marlin 1's planner).
double jerk_junction(const Axes& axis, double v, double safe, const Axes& jerk,
                     const Previous& prev) {
  const bool prev_faster = prev.feed > v;
  const double slower = prev_faster ? v / prev.feed : prev.feed / v;
  double junction = prev_faster ? v : prev.feed;
  double factor = 1;
  bool limited = false;
  for (int k = 0; k < 4; ++k) {
    double v_exit = prev.axis[k], v_entry = axis[k];
    if (prev_faster) v_exit *= slower;
    if (limited) v_exit *= factor, v_entry *= factor;
    // Coasting on, or reversing: the jerk the axis feels at the junction.
    const double j =
        v_exit > v_entry
            ? (v_entry > 0 || v_exit < 0 ? v_exit - v_entry : std::max(v_exit, -v_entry))
            : (v_entry < 0 || v_exit > 0 ? v_entry - v_exit : std::max(-v_exit, v_entry));
    if (j > jerk[k]) factor *= jerk[k] / j, limited = true;
  }
  if (limited) junction *= factor;
  const double threshold = junction * 0.99;
  if (prev.safe > threshold && safe > threshold) junction = safe;
  return junction;
}

// acos(t) for t in [0, 1) as Marlin 2 computes it for short moves at gentle turns: π/2 minus
// W. R. Franklin's minimax polynomial for asin (error ≤ 0.033 rad; it never returns less
// than 0.033, which keeps a nearly straight junction's arc limit finite).
double firmware_acos(double t) {
  const double asin_t =
      0.032843707 +
      t * (-1.451838349 +
           t * (29.66153956 +
                t * (-131.1123477 + t * (262.8130562 + t * (-242.7199627 + t * 84.31466202)))));
  return M_PI / 2 - asin_t;
}

// Marlin 2's junction deviation δ: the corner is driven as an arc that stays within δ of it,
// at the junction's acceleration a_j: v² = a_j δ sin(θ/2) / (1 − sin(θ/2)), θ the angle between
// the two directions; a move under 1 mm turning by less than 45° as an arc through its length
// instead.
// Never faster than either move. A full reversal stops.
double deviation_junction(const Axes& unit, double v, double a, double d, const Axes& accel,
                          double deviation, const Previous& prev) {
  double cos_t = 0;  // cosine of the corner's inner angle (the previous direction reversed)
  for (int k = 0; k < 4; ++k) cos_t -= prev.unit[k] * unit[k];
  if (cos_t > 0.999999) return 0;
  cos_t = std::max(cos_t, -0.999999);
  Axes turn{};
  double turn_norm = 0;
  for (int k = 0; k < 4; ++k) turn[k] = unit[k] - prev.unit[k], turn_norm += turn[k] * turn[k];
  turn_norm = std::sqrt(turn_norm);
  double a_j = a;  // the acceleration the turn may use: each axis within its own limit
  for (int k = 0; k < 4; ++k)
    if (turn[k] != 0 && accel[k] > 0) a_j = std::min(a_j, std::abs(accel[k] * turn_norm / turn[k]));
  const double sin_half = std::sqrt(0.5 * (1 - cos_t));
  double v2 = a_j * deviation * sin_half / (1 - sin_half);
  if (d < 1 && cos_t < -0.7071067812) v2 = std::min(v2, d * a_j / firmware_acos(-cos_t));
  v2 = std::min({v2, v * v, prev.feed * prev.feed});
  return std::sqrt(v2);
}

// One G0/G1 as a block with its junction speed (PrusaSlicer's process_G1), or none when it
// moves nothing.
bool make_block(const GcodeMove& m, const Limits& L, Previous& prev, bool first, Block& b) {
  const Vec3 dxyz = m.to - m.from;
  const Axes delta{dxyz.x(), dxyz.y(), dxyz.z(), m.de};
  double d = dxyz.norm();
  const bool e_only = d < 1e-9;
  if (e_only) d = std::abs(m.de);
  if (d < 1e-9) return false;
  const bool extruding = m.de > 0 && !e_only;
  double v = std::isnan(m.feed) ? 25.0 : m.feed / 60.0;
  v = std::max(v, extruding ? L.min_extruding_ : L.min_travel_);
  Axes axis{}, unit{};
  for (int k = 0; k < 4; ++k) axis[k] = v * delta[k] / d, unit[k] = delta[k] / d;
  double scale = 1;
  for (int k = 0; k < 4; ++k)
    if (L.feed_[k] > 0 && std::abs(axis[k]) > L.feed_[k])
      scale = std::min(scale, L.feed_[k] / std::abs(axis[k]));
  v *= scale;
  for (double& s : axis) s *= scale;
  double a = e_only ? L.retract_ : extruding ? L.print_ : L.travel_;
  for (int k = 0; k < 4; ++k)
    if (L.accel_[k] > 0 && std::abs(delta[k]) > 1e-12 && a * std::abs(delta[k]) / d > L.accel_[k])
      a = L.accel_[k] * d / std::abs(delta[k]);
  double safe = 0, junction = 0;  // with junction deviation a block may always stop at rest
  const bool after_motion = !first && prev.feed > 1e-4;
  if (L.deviation_ > 0) {
    if (after_motion) junction = deviation_junction(unit, v, a, d, L.accel_, L.deviation_, prev);
  } else {
    safe = v;
    for (int k = 0; k < 4; ++k)
      if (std::abs(axis[k]) > L.jerk_[k]) safe = std::min(safe, L.jerk_[k]);
    junction = after_motion ? jerk_junction(axis, v, safe, L.jerk_, prev) : safe;
  }
  const double allowable = max_allowable(-a, safe, d);
  b.d = d, b.a = a, b.cruise = v, b.safe = safe;
  b.entry = std::min(junction, allowable);
  b.max_entry = junction;
  b.nominal_length = v <= allowable;
  prev.feed = v, prev.safe = safe, prev.axis = axis, prev.unit = unit;
  return true;
}

// The look-ahead: each block's entry lowered so the one before can slow to it (reverse), and
// so it can be reached from the one before (forward).
void plan(std::vector<Block>& blocks) {
  for (std::size_t i = blocks.size(); i-- > 1;) {
    Block& b = blocks[i - 1];
    const Block& next = blocks[i];
    if (b.entry == b.max_entry) continue;
    b.entry = !b.nominal_length && b.max_entry > next.entry
                  ? std::min(b.max_entry, max_allowable(-b.a, next.entry, b.d))
                  : b.max_entry;
  }
  for (std::size_t i = 1; i < blocks.size(); ++i) {
    const Block& prev = blocks[i - 1];
    Block& b = blocks[i];
    if (!prev.nominal_length && prev.entry < b.entry)
      b.entry = std::min(b.entry, max_allowable(-prev.a, prev.entry, prev.d));
  }
}

// G4 P<ms> or S<s>.
double dwell(std::string_view raw) {
  core::Tokenizer tok(raw.substr(0, raw.find(';')));
  const auto cmd = tok.next();
  if (cmd != "G4" && cmd != "g4") return 0;
  double t = 0;
  for (auto w = tok.next(); !w.empty(); w = tok.next()) {
    const auto v = core::parse_double(w.substr(1));
    if (!v || !std::isfinite(*v) || *v < 0) continue;
    if (w[0] == 'P' || w[0] == 'p') t = *v / 1000.0;
    if (w[0] == 'S' || w[0] == 's') t = *v;
  }
  return std::min(t, 86400.0);
}

}  // namespace

// The planner's queue, as PrusaSlicer's GCodeProcessor keeps it after the firmware: once
// 256 blocks wait, all but the last 64 are planned and timed for good. A block's time then no
// longer waits for the whole file (the bunny's blocks took 67 MB), and the estimate is
// PrusaSlicer's, whose look-ahead ends there too.
constexpr std::size_t kQueue = 64, kRefresh = 4 * kQueue;

struct PrintTimer::Impl {
  explicit Impl(const MachineLimits& m) : L(m) {}
  Limits L;
  Previous prev;
  bool moved = false;         // a block was made (the first starts at rest)
  std::vector<Block> blocks;  // the queue
  std::vector<double> extra;  // per line: its dwell, and the time of the blocks done on it
  // Plans the queue and times all but its last `keep` blocks, which stay queued.
  void settle(std::size_t keep) {
    plan(blocks);
    const std::size_t done = blocks.size() - std::min(keep, blocks.size());
    for (std::size_t k = 0; k < done; ++k) {
      const double exit = k + 1 < blocks.size() ? blocks[k + 1].entry : blocks[k].safe;
      extra[blocks[k].line] += blocks[k].time(exit);
    }
    blocks.erase(blocks.begin(), blocks.begin() + static_cast<std::ptrdiff_t>(done));
  }
};

PrintTimer::PrintTimer(const MachineLimits& limits) : impl_(std::make_unique<Impl>(limits)) {
  impl_->blocks.reserve(kRefresh + 1);
}
PrintTimer::~PrintTimer() = default;

void PrintTimer::reserve(std::size_t lines) {
  reserve_huge(impl_->extra, lines);
}

void PrintTimer::line(const GcodeLine& l, const GcodeMove* move) {
  Impl& s = *impl_;
  const std::size_t i = s.extra.size();
  s.extra.push_back(0.0);
  if (l.kind == GcodeLine::Kind::move && move) {
    Block b;
    if (make_block(*move, s.L, s.prev, !s.moved, b)) {
      b.line = i, s.blocks.push_back(b), s.moved = true;
      if (s.blocks.size() > kRefresh) s.settle(kQueue);
    }
  } else if (l.kind == GcodeLine::Kind::text && !l.raw.empty()) {
    s.L.read(l.raw);
    s.extra[i] = dwell(l.raw);
  }
}

PrintTime PrintTimer::finish() {
  Impl& s = *impl_;
  s.settle(0);
  // Each line's time becomes its start, in place.
  std::vector<double>& spent = s.extra;
  double at = 0;
  for (double& s_i : spent) {
    const double own = s_i;
    s_i = at;
    at += own;
  }
  spent.push_back(at);
  PrintTime t;
  t.line_start = std::move(spent);
  t.total = at;
  return t;
}

PrintTime estimate_print_time(const GcodeProgram& program, const MachineLimits& limits) {
  PrintTimer timer(limits);
  for (const GcodeLine& l : program.lines)
    timer.line(l, l.kind == GcodeLine::Kind::move ? &program.moves[static_cast<std::size_t>(l.move)]
                                                  : nullptr);
  return timer.finish();
}

std::string format_duration(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  const long d = s / 86400, h = s / 3600 % 24, m = s / 60 % 60, sec = s % 60;
  char buf[64];
  if (d > 0)
    std::snprintf(buf, sizeof buf, "%ldd %ldh %ldm %lds", d, h, m, sec);
  else if (h > 0)
    std::snprintf(buf, sizeof buf, "%ldh %ldm %lds", h, m, sec);
  else if (m > 0)
    std::snprintf(buf, sizeof buf, "%ldm %lds", m, sec);
  else
    std::snprintf(buf, sizeof buf, "%lds", sec);
  return buf;
}

}  // namespace nonplanar
