// Mapping another slicer's planar G-code of the normalised mesh back onto the curved layers
// (issue: libslic3r engine). Notation as in map_segment.hpp; E is filament length (mm).
//
// The file keeps its own program: start and end G-code, temperatures, fan, speeds and
// retractions pass untouched. Inside the print (first ;LAYER_CHANGE to the ;TYPE:Custom
// that follows the last typed extrusion), each G0/G1 is mapped: an extrusion is resampled
// like the built-in engine's paths and each piece's E scaled by its own 3D length and layer
// thickness against the planar ones (L·t / (L_p·h)); a wipe follows the layer with its E
// spread over the pieces; a travel over curved layers rises above the layer's highest point
// (or, for a hop under 0.6 mm, its slope's reach) and comes down at the target, as the
// built-in writer does; top skins are re-ordered low to high (order_top_skins).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <optional>

#include "deform/map_segment.hpp"
#include "io/mesh_buffer.hpp"
#include "nonplanar/deform.hpp"

namespace nonplanar {
namespace {

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

struct Move {
  int line = 0;
  Vec3 from, to;  ///< planar
  double de = 0;  ///< filament pushed (negative: retraction)
  bool has_xy = false, has_z = false, has_e = false;
  double f = kNone;     ///< feed rate, if the line had one
  double feed = kNone;  ///< the feed rate in force for it (its own or the last one given)
  bool wipe = false;
  std::string type;
  double width = 0.45, h = 0.2;  ///< ;WIDTH: and the planar layer's ;HEIGHT:
  bool extruding() const { return de > 0 && has_xy && (to - from).head<2>().norm() > 1e-9; }
};

// One input line: untouched text, or a move of the print (index into moves), or a layer's
// ;Z: / ;HEIGHT: comment (rewritten).
struct Item {
  enum Kind { text, move, z_comment, height_comment, e_reset, e_mode, xyz_relative } kind = text;
  std::string_view raw;
  int index = -1;
  double value = 0;  ///< e_reset: the new E; e_mode: 1 relative, 0 absolute
  int layer = -1;
};

ExtrusionRole role_of(const std::string& type) {
  if (type == "External perimeter" || type == "Overhang perimeter")
    return ExtrusionRole::external_perimeter;
  if (type == "Perimeter") return ExtrusionRole::perimeter;
  if (type == "Internal infill") return ExtrusionRole::internal_infill;
  if (type == "Top solid infill" || type == "Ironing") return ExtrusionRole::top_solid_infill;
  if (type == "Skirt/Brim" || type == "Skirt" || type == "Brim") return ExtrusionRole::skirt;
  return ExtrusionRole::solid_infill;
}

class Writer {
 public:
  Writer(bool rel_e) : rel_e_(rel_e) {}
  std::string out;
  void raw(std::string_view s) {
    out.append(s);
    out.push_back('\n');
  }
  void line(const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
    char buf[256];
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    raw(buf);
  }
  // A move from `from` to p (mapped) pushing e mm of filament at feed rate f; only the axes
  // that change are written, E and F only where given (NaN: not given).
  void move(const Vec3& p, const Vec3& from, double e, double f) {
    std::string s = "G1";
    char buf[64];
    if (std::abs(p.x() - from.x()) > 5e-4 || std::abs(p.y() - from.y()) > 5e-4) {
      std::snprintf(buf, sizeof buf, " X%.3f Y%.3f", p.x(), p.y());
      s += buf;
    }
    if (std::abs(p.z() - from.z()) > 5e-4) {
      std::snprintf(buf, sizeof buf, " Z%.3f", p.z());
      s += buf;
    }
    if (!std::isnan(e)) {
      e_ += e;
      std::snprintf(buf, sizeof buf, " E%.5f", rel_e_ ? e : e_);
      s += buf;
    }
    if (!std::isnan(f)) {
      std::snprintf(buf, sizeof buf, " F%d", static_cast<int>(std::lround(f)));
      s += buf;
    }
    if (s.size() > 2) raw(s);
  }
  void set_e(double e) { e_ = e; }
  void set_relative(bool r) { rel_e_ = r; }

 private:
  bool rel_e_;
  double e_ = 0;
};

// Top skins on a slope, low to high (DESIGN.md §3: a line printed beside a higher line of the
// same layer drags the nozzle's flat through it). In each run of "Top solid infill" of `seq`
// (one layer), the strokes (unbroken extrusions) are sorted by mean mapped height and each
// starts at its low end; the travels between them are made anew, with the run's own
// retraction around them and its extrusion feed rate after. The run's trailing wipes become
// plain retractions (their path retraced the old last stroke). New and reversed moves are
// appended to `moves` and `mapped`.
void order_top_skins(std::vector<Item>& seq, std::vector<Move>& moves,
                     std::vector<ExtrusionPath>& mapped) {
  auto is_type = [](const Item& it, std::string_view t) {
    return it.kind == Item::text && it.raw.rfind(t, 0) == 0;
  };
  auto mean_z = [&](const std::vector<int>& stroke) {
    double z = 0;
    std::size_t n = 0;
    for (int m : stroke)
      for (const Vec3& v : mapped[static_cast<std::size_t>(m)].points) z += v.z(), ++n;
    return n ? z / static_cast<double>(n) : 0.0;
  };
  auto add = [&](Move m, ExtrusionPath p) {
    moves.push_back(std::move(m));
    mapped.push_back(std::move(p));
    Item it;
    it.kind = Item::move;
    it.index = static_cast<int>(moves.size()) - 1;
    return it;
  };
  for (std::size_t s = 0; s < seq.size(); ++s) {
    if (!is_type(seq[s], ";TYPE:Top solid infill")) continue;
    std::size_t e = s + 1;
    while (e < seq.size() && !is_type(seq[e], ";TYPE:")) ++e;
    std::vector<std::vector<int>> strokes;
    std::vector<Item> head, tail;  // the run's other lines; what follows its last stroke
    double ret = 0, ret_f = kNone, unret_f = kNone, travel_f = kNone, print_f = kNone;
    bool in_stroke = false;
    std::size_t last = s;
    for (std::size_t k = s + 1; k < e; ++k)
      if (seq[k].kind == Item::move && moves[static_cast<std::size_t>(seq[k].index)].extruding())
        last = k;
    for (std::size_t k = s + 1; k < e; ++k) {
      const Item& it = seq[k];
      if (k > last) {
        if (it.kind != Item::move) {
          tail.push_back(it);
          continue;
        }
        Move m = moves[static_cast<std::size_t>(it.index)];
        if (m.wipe && m.has_xy) {  // a wipe: its retraction, in place
          m.has_xy = false, m.to = m.from;
          tail.push_back(add(std::move(m), {}));
        } else {
          tail.push_back(it);
        }
        continue;
      }
      if (it.kind != Item::move) {
        if (it.kind != Item::e_reset) head.push_back(it);  // E is ours inside the run
        continue;
      }
      const Move& m = moves[static_cast<std::size_t>(it.index)];
      if (m.extruding()) {
        if (!in_stroke) strokes.emplace_back();
        strokes.back().push_back(it.index);
        in_stroke = true;
        continue;
      }
      in_stroke = false;
      const bool e_only = !m.has_xy && !m.has_z;
      if (e_only && m.has_e && m.de < 0 && ret == 0) ret = -m.de, ret_f = m.f;
      if (e_only && m.has_e && m.de > 0 && std::isnan(unret_f)) unret_f = m.f;
      if (e_only && !m.has_e && !std::isnan(m.f) && strokes.empty()) print_f = m.f;
      if (m.has_xy && !m.has_e && std::isnan(travel_f)) travel_f = m.f;
    }
    if (strokes.empty()) continue;
    std::stable_sort(strokes.begin(), strokes.end(),
                     [&](const auto& a, const auto& b) { return mean_z(a) < mean_z(b); });
    std::vector<Item> out{seq[s]};
    out.insert(out.end(), head.begin(), head.end());
    const Move& first = moves[static_cast<std::size_t>(strokes.front().front())];
    Vec3 prev = first.from;
    for (const auto& stroke : strokes) {
      const ExtrusionPath& a = mapped[static_cast<std::size_t>(stroke.front())];
      const ExtrusionPath& b = mapped[static_cast<std::size_t>(stroke.back())];
      const bool reverse = a.points.front().z() > b.points.back().z() + 1e-9;
      const Move& m0 = moves[static_cast<std::size_t>(reverse ? stroke.back() : stroke.front())];
      const Vec3 start = reverse ? m0.to : m0.from;
      Move travel = m0;
      travel.from = prev, travel.to = start, travel.has_xy = true, travel.has_z = false;
      travel.has_e = false, travel.de = 0, travel.wipe = false, travel.f = travel_f;
      Move r = travel;
      r.has_xy = false, r.from = r.to = prev, r.has_e = true, r.de = -ret, r.f = ret_f;
      const bool hop = ret > 0 && (start - prev).head<2>().norm() > 1.0;
      if (hop) out.push_back(add(r, {}));
      out.push_back(add(travel, {}));
      if (hop) {
        r.from = r.to = start, r.de = ret, r.f = unret_f;
        out.push_back(add(r, {}));
      }
      bool first_piece = true;
      for (std::size_t q = 0; q < stroke.size(); ++q) {
        const int idx = stroke[reverse ? stroke.size() - 1 - q : q];
        Move m = moves[static_cast<std::size_t>(idx)];
        ExtrusionPath p = mapped[static_cast<std::size_t>(idx)];
        if (reverse) {
          std::swap(m.from, m.to);
          std::reverse(p.points.begin(), p.points.end());
          std::reverse(p.height.begin(), p.height.end());
        }
        if (first_piece && std::isnan(m.f)) m.f = print_f;
        first_piece = false;
        prev = m.to;
        out.push_back(add(std::move(m), std::move(p)));
      }
    }
    out.insert(out.end(), tail.begin(), tail.end());
    seq.erase(seq.begin() + static_cast<long>(s), seq.begin() + static_cast<long>(e));
    seq.insert(seq.begin() + static_cast<long>(s), out.begin(), out.end());
    s += out.size() - 1;
  }
}

// The file's first retraction inside the print: how far and how fast, and how fast it is given
// back (none: length 0).
struct Retraction {
  double length = 0, f = kNone, back_f = kNone;
};

// Cuts each extrusion of one layer (`seq`) to where clip.margin(·, ·, z) >= 0: kept pieces
// extrude their share of E, the rest become travels, retracted around when longer than 2 mm
// (as PrusaSlicer's retract_before_travel). Crossings are found on 0.05 mm steps and bisected.
// New moves are appended to `moves` and `mapped`. `samples` counts the margins looked up; past
// 50 million (a broken file, not a print) it stops and returns the line it was on (else 0).
int clip_layer(std::vector<Item>& seq, std::vector<Move>& moves, std::vector<ExtrusionPath>& mapped,
               const LayerClip& clip, double z, const Retraction& ret, std::size_t& samples) {
  auto add = [&](Move m, std::vector<Item>& out) {
    moves.push_back(std::move(m));
    mapped.emplace_back();
    Item it;
    it.kind = Item::move;
    it.index = static_cast<int>(moves.size()) - 1;
    out.push_back(it);
  };
  std::vector<Item> out;
  out.reserve(seq.size());
  // The give-back of a retraction around cut-away travel: held while the travel goes on (the
  // next extrusion cut away too, as a whole perimeter above the core often is), added before
  // anything else.
  std::optional<Move> owed;
  auto settle = [&] {
    if (owed) add(*owed, out), owed.reset();
  };
  for (const Item& it : seq) {
    if (it.kind != Item::move || !moves[static_cast<std::size_t>(it.index)].extruding()) {
      settle();
      out.push_back(it);
      continue;
    }
    const Move m = moves[static_cast<std::size_t>(it.index)];
    auto at = [&](double s) { return Vec3(m.from + s * (m.to - m.from)); };
    auto g = [&](double s) {
      const Vec3 p = at(s);
      return clip.margin(p.x(), p.y(), z);
    };
    // Pieces [s_k, s_k+1] between the crossings, each kept or not.
    const double len = (m.to - m.from).head<2>().norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / 0.05)));
    samples += static_cast<std::size_t>(n) + 1;
    if (samples > 50'000'000) return m.line;
    std::vector<double> cuts{0.0};
    double s0 = 0, g0 = g(0);
    for (int k = 1; k <= n; ++k) {
      const double s1 = static_cast<double>(k) / n, g1 = g(s1);
      if ((g0 >= 0) != (g1 >= 0)) {
        double lo = s0, hi = s1;
        for (int b = 0; b < 30; ++b) {
          const double mid = 0.5 * (lo + hi);
          ((g(mid) >= 0) == (g0 >= 0) ? lo : hi) = mid;
        }
        cuts.push_back(0.5 * (lo + hi));
      }
      s0 = s1, g0 = g1;
    }
    cuts.push_back(1.0);
    // Neighbouring pieces on the same side are one, and a piece under 1 µm takes its
    // neighbour's side: a margin of exactly 0 (a flat floor the core's boundaries were
    // snapped to) flips back and forth within a step, or touches 0 at one point.
    std::vector<double> merged{0.0};
    std::vector<char> kept;  // per merged piece
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
      const bool sliver = k > 0 && (cuts[k + 1] - cuts[k]) * len < 1e-3;
      const char in = sliver ? kept.back() : g(0.5 * (cuts[k] + cuts[k + 1])) >= 0;
      if (k > 0 && in != kept.back()) merged.push_back(cuts[k]);
      if (k == 0 || in != kept.back()) kept.push_back(in);
    }
    merged.push_back(1.0);
    cuts = std::move(merged);
    if (cuts.size() == 2 && kept[0]) {
      out.push_back(it);
      continue;
    }
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
      Move piece = m;
      piece.from = at(cuts[k]), piece.to = at(cuts[k + 1]);
      piece.f = k == 0 ? m.f : kNone;
      if (kept[k]) {
        if (owed) settle(), piece.f = m.feed;  // after the give-back's feed rate
        piece.de = m.de * (cuts[k + 1] - cuts[k]);
        add(piece, out);
        continue;
      }
      piece.de = 0, piece.has_e = false;
      const bool hop = ret.length > 0 && (owed || (piece.to - piece.from).head<2>().norm() > 2.0);
      Move r = piece;
      r.has_xy = false, r.has_e = true;
      if (hop && !owed) {
        r.to = r.from, r.de = -ret.length, r.f = ret.f;
        add(r, out);
      }
      if (hop) piece.f = m.feed;
      add(piece, out);
      if (hop) r.from = r.to = piece.to, r.de = ret.length, r.f = ret.back_f, owed = r;
    }
  }
  settle();
  seq = std::move(out);
  return 0;
}

}  // namespace

Expected<ForeignGcode> map_foreign_gcode(std::string_view text, const LayerField& field,
                                         const MapBackParams& params, const Context& ctx,
                                         const ForeignMapOptions& options) {
  if (!(params.tolerance > 0)) return Error{Status::invalid_argument, "map tolerance: must be > 0"};
  // Split into lines; find where the print ends: the first ;TYPE:Custom after the last other
  // ;TYPE: (PrusaSlicer's and OrcaSlicer's end G-code follow one), else the end of the file.
  std::vector<std::string_view> lines;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view l = text.substr(start, end - start);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    lines.push_back(l);
    start = end + 1;
  }
  std::size_t first_layer = lines.size(), last_typed = 0, print_end = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string_view l = lines[i];
    if (first_layer == lines.size() && l.rfind(";LAYER_CHANGE", 0) == 0) first_layer = i;
    if (l.rfind(";TYPE:", 0) == 0 && l.rfind(";TYPE:Custom", 0) != 0) last_typed = i;
  }
  if (first_layer == lines.size())
    return Error{Status::parse_error, "no ;LAYER_CHANGE: not a layered G-code file"};
  for (std::size_t i = std::max(last_typed, first_layer); i < lines.size(); ++i)
    if (lines[i].rfind(";TYPE:Custom", 0) == 0) {
      print_end = i;
      break;
    }

  // Pass 1: parse every line, keeping state across the whole file.
  std::vector<Move> moves;
  std::vector<Item> items;
  std::vector<double> layer_h;  // planar ;HEIGHT: per layer
  std::vector<double> layer_z;  // planar ;Z: per layer (its top)
  Retraction retraction;
  std::string fan_at_print;
  double feed = kNone;
  Vec3 pos(0, 0, 0);
  double e = 0, width = 0.45, h = 0.2;
  bool rel_e = false, rel_xyz = false, wipe = false, rel_e_at_print = false;
  bool layer_header = false;  // between ;LAYER_CHANGE and the layer's ;HEIGHT:
  double e_at_end = 0, e_at_print = 0;
  bool rel_e_at_end = false, rel_xyz_at_end = false;
  std::string type;
  int layer = -1;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i) + 1;
    auto fail = [&](const std::string& why) {
      return Error{Status::parse_error, "line " + std::to_string(line) + ": " + why};
    };
    const bool in_print = i >= first_layer && i < print_end;
    if (i == first_layer) rel_e_at_print = rel_e, e_at_print = e;
    if (i == print_end) e_at_end = e, rel_e_at_end = rel_e, rel_xyz_at_end = rel_xyz;
    std::string_view l = lines[i];
    Item item;
    item.raw = l;
    item.layer = layer;
    const std::size_t semi = l.find(';');
    if (semi != std::string_view::npos) {
      const std::string_view c = l.substr(semi);
      if (c.rfind(";TYPE:", 0) == 0) type = std::string(c.substr(6));
      if (c.rfind(";WIDTH:", 0) == 0)
        if (auto w = io::parse_double(c.substr(7)); w && *w > 0) width = *w;
      if (c.rfind(";WIPE_START", 0) == 0) wipe = true;
      if (c.rfind(";WIPE_END", 0) == 0) wipe = false;
      if (in_print && c.rfind(";LAYER_CHANGE", 0) == 0)
        item.layer = ++layer, layer_h.push_back(h), layer_z.push_back(pos.z() + h),
        layer_header = true;
      // The layer's thickness is the ;HEIGHT: of its header; later ones are a bead's (a
      // bridge's is the nozzle's diameter) and pass untouched.
      if (in_print && layer_header && c.rfind(";HEIGHT:", 0) == 0 && semi == 0) {
        if (auto v = io::parse_double(c.substr(8)); v && *v > 0) h = *v, layer_h.back() = h;
        item.kind = Item::height_comment;
        layer_header = false;
      }
      if (in_print && c.rfind(";Z:", 0) == 0 && semi == 0) {
        item.kind = Item::z_comment;
        if (auto v = io::parse_double(c.substr(3)); v && layer >= 0)
          layer_z[static_cast<std::size_t>(layer)] = *v;
      }
      l = l.substr(0, semi);
    }
    io::Tokenizer tok(l);
    const std::string_view cmd = tok.next();
    if (cmd.empty()) {
      items.push_back(item);
      continue;
    }
    const char kind = static_cast<char>(std::toupper(static_cast<unsigned char>(cmd[0])));
    const auto num = io::parse_int(cmd.substr(1));
    const bool fan = kind == 'M' && num && (*num == 106 || *num == 107);
    if (fan && i < first_layer) fan_at_print = std::string(lines[i]);
    if (kind == 'M' && num && (*num == 82 || *num == 83)) {
      rel_e = *num == 83;
      item.kind = Item::e_mode, item.value = rel_e;
    }
    if (kind == 'G' && num && (*num == 90 || *num == 91)) {
      rel_xyz = *num == 91;
      if (rel_xyz && in_print) item.kind = Item::xyz_relative;  // written absolute: see below
    }
    if (kind == 'G' && num && *num == 92) {
      for (std::string_view w = tok.next(); !w.empty(); w = tok.next()) {
        const auto v = io::parse_double(w.substr(1));
        const char a = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
        if (!v) {
          if (in_print) return fail("bad number in G92");
          continue;
        }
        if (a == 'E') e = *v, item.kind = Item::e_reset, item.value = *v;
        if (a == 'X') pos.x() = *v;
        if (a == 'Y') pos.y() = *v;
        if (a == 'Z') pos.z() = *v;
      }
    } else if (kind == 'G' && num && (*num == 0 || *num == 1)) {
      Move m;
      m.line = line, m.from = pos, m.to = pos;
      for (std::string_view w = tok.next(); !w.empty(); w = tok.next()) {
        const char a = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
        const auto v = io::parse_double(w.substr(1));
        if (!v) {
          if (in_print) return fail("bad number in '" + std::string(w.substr(0, 30)) + "'");
          continue;
        }
        if (a == 'X')
          m.to.x() = rel_xyz ? m.to.x() + *v : *v, m.has_xy = true;
        else if (a == 'Y')
          m.to.y() = rel_xyz ? m.to.y() + *v : *v, m.has_xy = true;
        else if (a == 'Z')
          m.to.z() = rel_xyz ? m.to.z() + *v : *v, m.has_z = true;
        else if (a == 'E')
          // G91 makes E relative too, as M83 does (Klipper, RepRapFirmware, Marlin 1 and
          // PrusaSlicer's viewer; read as absolute, a G91 retraction became 75x extrusion).
          m.has_e = true, m.de = rel_e || rel_xyz ? *v : *v - e, e = rel_e || rel_xyz ? e + *v : *v;
        else if (a == 'F')
          m.f = *v;
        else if (in_print)
          return fail("unknown word '" + std::string(w.substr(0, 20)) + "' in a move");
      }
      // No printer is 10 m across: such a coordinate is a broken file, and mapping its
      // moves in 1 mm pieces would not fit in memory. The move's start counts too: the start
      // G-code (not checked) may have left the nozzle there.
      if (in_print && std::max(m.to.cwiseAbs().maxCoeff(), m.from.cwiseAbs().maxCoeff()) > 1e4)
        return fail("coordinate beyond 10 m: not a print this can map");
      pos = m.to;
      if (!std::isnan(m.f)) feed = m.f;
      m.feed = feed;
      if (in_print && !m.has_xy && !m.has_z && m.has_e) {
        if (m.de < 0 && retraction.length == 0) retraction.length = -m.de, retraction.f = m.f;
        if (m.de > 0 && std::isnan(retraction.back_f)) retraction.back_f = m.f;
      }
      if (in_print) {
        if (layer < 0) return fail("a move before the first layer");
        m.wipe = wipe, m.type = type, m.width = width, m.h = h;
        item.kind = Item::move;
        item.index = static_cast<int>(moves.size());
        moves.push_back(std::move(m));
      }
    } else if (in_print) {
      if (kind == 'G' && num && (*num == 2 || *num == 3))
        return fail("arc move (G2/G3) cannot be mapped onto curved layers; turn arc fitting off");
      const bool known = kind == 'M' || kind == 'T' ||
                         (kind == 'G' && num &&
                          (*num == 4 || *num == 10 || *num == 11 || *num == 21 || *num == 90 ||
                           *num == 91 || *num == 92));
      if (!known || (kind != 'T' && !num))
        return fail("'" + std::string(cmd.substr(0, 20)) +
                    "' inside the print cannot be mapped onto curved layers");
    }
    items.push_back(item);
  }
  if (print_end == lines.size()) e_at_end = e, rel_e_at_end = rel_e, rel_xyz_at_end = rel_xyz;
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};

  // Pass 2, a layer at a time: map its extrusions and wipes first (their highest point and
  // steepest slope set how its travels clear it), then write its lines in order.
  ForeignGcode out;
  out.layers.resize(layer_h.size());
  Writer w(rel_e_at_print);
  std::vector<ExtrusionPath> mapped(moves.size());
  Vec3 at(0, 0, 0);  // the nozzle, mapped
  std::size_t points = 0;
  std::size_t i = 0;
  for (; i < first_layer; ++i) w.raw(items[i].raw);
  out.print_begin = w.out.size();
  out.relative_e_at_print = rel_e_at_print, out.e_at_print = e_at_print;
  out.fan_at_print = fan_at_print;
  if (!moves.empty()) at = moves.front().from;
  if (options.start) at = *options.start;
  double pending = options.start_retracted;  // given back at the first E move
  double retracted = 0;
  std::vector<char> dropped(layer_h.size(), 0);
  std::size_t clip_samples = 0;
  w.set_e(e_at_print);  // absolute E continues from the untouched start G-code
  while (i < print_end) {
    std::size_t j = i + 1;
    while (j < print_end && items[j].raw.rfind(";LAYER_CHANGE", 0) != 0) ++j;
    const int li = items[i].layer;
    const std::size_t lu = static_cast<std::size_t>(std::max(li, 0));
    LayerToolpaths& L = out.layers[lu];
    L.max_z = -1e300;
    std::vector<Item> seq(items.begin() + static_cast<long>(i),
                          items.begin() + static_cast<long>(j));
    const auto cover = options.clip ? options.clip->cover(layer_z[lu]) : LayerClip::Cover::all;
    if (cover == LayerClip::Cover::none) {
      // Left out, but for what it tells the printer (temperatures, E mode); not the fan, which
      // follows the layers printed instead (and is turned off at the end).
      for (const Item& it : seq)
        if (it.kind == Item::text || it.kind == Item::e_mode)
          if (!it.raw.empty() && std::toupper(static_cast<unsigned char>(it.raw[0])) == 'M' &&
              it.raw.rfind("M106", 0) != 0 && it.raw.rfind("M107", 0) != 0) {
            w.raw(it.raw);
            if (it.kind == Item::e_mode) w.set_relative(it.value != 0);
          }
      dropped[lu] = 1;
      i = j;
      continue;
    }
    if (cover == LayerClip::Cover::some)
      if (const int bad =
              clip_layer(seq, moves, mapped, *options.clip, layer_z[lu], retraction, clip_samples))
        return Error{Status::invalid_argument,
                     "line " + std::to_string(bad) + ": more than 50 million clip samples"};
    // Map the layer's extrusions and wipes.
    for (const Item& it : seq) {
      if (it.kind != Item::move) continue;
      const Move& m = moves[static_cast<std::size_t>(it.index)];
      if (!m.has_xy || !(m.extruding() || (m.wipe && m.de <= 0))) continue;
      ExtrusionPath& p = mapped[static_cast<std::size_t>(it.index)];
      const Mapped a = map_point(field, m.from, m.h), b = map_point(field, m.to, m.h);
      p.points.push_back(a.p);
      p.height.push_back(a.height);
      map_segment(field, m.from, a, m.to, b, m.h, params.tolerance, 0, p);
      points += p.points.size();
      if (points > 50'000'000)
        return Error{Status::invalid_argument,
                     "line " + std::to_string(m.line) + ": more than 50 million mapped points"};
      for (std::size_t q = 0; q < p.points.size(); ++q) {
        L.max_z = std::max(L.max_z, p.points[q].z());
        if (q == 0) continue;
        const double dxy = (p.points[q] - p.points[q - 1]).head<2>().norm();
        if (dxy > 1e-3)
          L.max_slope =
              std::max(L.max_slope, std::abs(p.points[q].z() - p.points[q - 1].z()) / dxy);
      }
    }
    if (L.max_z < -1e299) L.max_z = 0;
    order_top_skins(seq, moves, mapped);
    // Write.
    double h_sum = 0;
    std::size_t h_n = 0;
    ExtrusionPath* run = nullptr;  // the gate's path being extended
    for (const Item& it : seq) {
      if (it.kind == Item::xyz_relative) {
        // Mapped moves are written absolute, so the printer stays in G90 through the print.
        w.raw("; G91 (relative XYZ) applied by nonplanar: the mapped moves are absolute");
        continue;
      }
      if (it.kind == Item::text || it.kind == Item::e_reset || it.kind == Item::e_mode) {
        w.raw(it.raw);
        if (it.kind == Item::e_reset) w.set_e(it.value);
        if (it.kind == Item::e_mode) w.set_relative(it.value != 0);
        continue;
      }
      if (it.kind == Item::z_comment || it.kind == Item::height_comment) {
        // Recomputed once the layer is written: placeholders filled below.
        w.raw(it.kind == Item::z_comment ? ";Z:@" : ";HEIGHT:@");
        continue;
      }
      const Move& m = moves[static_cast<std::size_t>(it.index)];
      const ExtrusionPath& p = mapped[static_cast<std::size_t>(it.index)];
      if (!p.points.empty()) {
        // Extrusion or wipe: one G1 per piece.
        const double lp = (m.to - m.from).norm();
        double l3 = 0;
        for (std::size_t q = 1; q < p.points.size(); ++q)
          l3 += (p.points[q] - p.points[q - 1]).norm();
        double f = m.f;
        if (pending != 0 && m.has_e) w.move(at, at, pending, kNone), pending = 0;
        if (!m.extruding() && m.has_e) retracted -= m.de;
        if (m.extruding() && !run) {
          ExtrusionPath g;
          g.role = role_of(m.type), g.width = m.width;
          g.points.push_back(p.points[0]);
          g.height.push_back(p.height[0]);
          L.paths.push_back(std::move(g));
          run = &L.paths.back();
        }
        for (std::size_t q = 1; q < p.points.size(); ++q) {
          const double seg = (p.points[q] - p.points[q - 1]).norm();
          double de;
          if (m.extruding()) {
            const double hq = 0.5 * (p.height[q] + p.height[q - 1]);
            de = lp > 0 ? m.de * (seg / lp) * (hq / m.h) : 0;
            run->points.push_back(p.points[q]);
            run->height.push_back(p.height[q]);
            h_sum += p.height[q], ++h_n;
          } else {
            de = l3 > 0 ? m.de * seg / l3 : 0;
          }
          w.move(p.points[q], at, m.has_e ? de : kNone, f);
          f = kNone;
          at = p.points[q];
        }
        if (!m.extruding()) run = nullptr;
        continue;
      }
      run = nullptr;
      if (!m.has_xy && !m.has_z) {  // retraction, F only
        if (m.has_e) retracted -= m.de;
        w.move(at, at, m.has_e ? m.de + pending : kNone, m.f);
        if (m.has_e) pending = 0;
        continue;
      }
      // A travel (or a Z move): to the target's place on its layer. A Z move stays where the
      // nozzle is (not where the file's start G-code left it, when options.start moved it).
      const Mapped target = map_point(field, m.has_xy ? m.to : Vec3(at.x(), at.y(), m.to.z()), m.h);
      const Vec3 to = target.p;
      const bool curved =
          target.p.z() != m.to.z() || !field.planar_at(m.from.x(), m.from.y()) ||
          !field.planar_along(m.from.head<2>(), m.to.head<2>(), field.t_of_zeta(m.to.z() - m.h),
                              field.t_of_zeta(m.to.z()));
      const double de = m.has_e ? m.de + pending : kNone;
      if (m.has_e) retracted -= m.de, pending = 0;
      const double lift = curved && m.has_xy ? travel_height(at, to, L.max_z, L.max_slope,
                                                             params.tip_radius, params.travel_lift)
                                             : kNone;
      if (!std::isnan(lift)) {
        const Vec3 up(at.x(), at.y(), lift), over(to.x(), to.y(), lift);
        w.move(up, at, kNone, m.f);
        w.move(over, up, kNone, kNone);
        w.move(to, over, de, kNone);
      } else {
        w.move(to, at, de, m.f);
      }
      at = to;
    }
    // Fill the layer's ;Z: (its highest point) and ;HEIGHT: (its mean thickness).
    char zbuf[32], hbuf[32];
    std::snprintf(zbuf, sizeof zbuf, ";Z:%.3f", L.max_z);
    std::snprintf(hbuf, sizeof hbuf, ";HEIGHT:%.3f",
                  h_n ? h_sum / static_cast<double>(h_n)
                      : layer_h[static_cast<std::size_t>(std::max(li, 0))]);
    for (const char* key : {";Z:@", ";HEIGHT:@"}) {
      const std::size_t at_key = w.out.rfind(key);
      if (at_key != std::string::npos)
        w.out.replace(at_key, std::string(key).size(), key[1] == 'Z' ? zbuf : hbuf);
    }
    L.z = L.max_z;
    L.height = layer_h[static_cast<std::size_t>(std::max(li, 0))];
    L.nonplanar = true;
    i = j;
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  }
  out.print_end = w.out.size();
  out.end_at = at, out.retracted = retracted, out.relative_e_at_end = rel_e_at_end;
  // The end G-code as written, after telling the firmware the file's own E (absolute E).
  if (print_end < lines.size() && !rel_e_at_end) w.line("G92 E%.5f", e_at_end);
  if (print_end < lines.size() && rel_xyz_at_end) w.raw("G91 ; as the file had it here");
  for (; i < lines.size(); ++i) w.raw(items[i].raw);
  out.text = std::move(w.out);
  for (std::size_t k = dropped.size(); k-- > 0;)
    if (dropped[k]) out.layers.erase(out.layers.begin() + static_cast<long>(k));
  return out;
}

}  // namespace nonplanar
