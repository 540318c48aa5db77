// The built-in engine's G-code: the start block, then each layer built as steps (LayerBuilder:
// position, retraction, lifted travels, extrusion; PrusaSlicer's preview annotations; no arcs)
// and written by the one writer (program/gcode_text.hpp), then the end block. Text is built in
// memory and written atomically, so a half-written file never exists under the final name.
#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

#include "core/atomic_file.hpp"
#include "core/huge_pages.hpp"
#include "gcode/object_labels.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/macros.hpp"
#include "program/gcode_text.hpp"
#include "program/printed_top.hpp"

namespace nonplanar {

namespace {
const char* flavor_name(GcodeFlavor f) {
  switch (f) {
    case GcodeFlavor::marlin2:
      return "marlin2";
    case GcodeFlavor::klipper:
      return "klipper";
    case GcodeFlavor::reprapfirmware:
      return "reprapfirmware";
  }
  return "marlin2";
}

// What PrusaSlicer knows of the print when it expands a block, from the layers written.
struct PrintFacts {
  Vec2 first_min{0, 0}, first_max{0, 0};  ///< footprint of the first layer's extrusions
  double max_layer_z = 0;                 ///< the highest point printed
  int layers = 0;
};

PrintFacts facts_of(const std::vector<LayerToolpaths>& layers, const PrintConfig& c) {
  PrintFacts f;
  f.first_min = f.first_max = c.bed_center();
  f.layers = static_cast<int>(layers.size());
  bool any = false;
  for (const LayerToolpaths& L : layers) f.max_layer_z = std::max({f.max_layer_z, L.z, L.max_z});
  if (layers.empty()) return f;
  Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const ExtrusionPath& p : layers.front().paths) {
    if (p.role == ExtrusionRole::skirt) continue;
    for (const Vec3& v : p.points) {  // the bead's outer edge, as PrusaSlicer's slice outline
      const Vec3 q = program::on_file_grid(v);
      lo = lo.cwiseMin(q.head<2>() - Vec2::Constant(0.5 * p.width));
      hi = hi.cwiseMax(q.head<2>() + Vec2::Constant(0.5 * p.width));
      any = true;
    }
  }
  if (any) f.first_min = lo, f.first_max = hi;
  return f;
}

std::vector<MacroValue> pair(const Vec2& v) {
  return {MacroValue::real(v.x()), MacroValue::real(v.y())};
}

// The variables every block sees: the profile's (profile_variables) and the print's facts.
MacroVariables block_variables(const PrintConfig& c, const PrintFacts& f) {
  MacroVariables v = profile_variables(c);
  v.set_vector("first_layer_print_min", pair(f.first_min));
  v.set_vector("first_layer_print_max", pair(f.first_max));
  v.set_vector("first_layer_print_size", pair(f.first_max - f.first_min));
  v.set("max_layer_z", MacroValue::real(f.max_layer_z));
  v.set("layer_z", MacroValue::real(f.max_layer_z));
  v.set("total_layer_count", MacroValue::integer(f.layers));
  v.set("zhop", MacroValue::integer(0));
  return v;
}

// One custom block, expanded and ending in a newline ("" stays "").
Expected<std::string> expand(const std::string& t, const MacroVariables& v, const char* key) {
  auto r = expand_macros(t, v, key);
  if (r && !r->empty() && r->back() != '\n') *r += '\n';
  return r;
}

// The command word of one line, upper-cased and without its comment: "M190", "G1", "".
std::string command_of(std::string_view line) {
  line = line.substr(0, line.find(';'));
  const auto a = line.find_first_not_of(" \t");
  if (a == std::string_view::npos) return {};
  const auto b = line.find_first_of(" \t", a);
  std::string w(line.substr(a, b == std::string_view::npos ? line.npos : b - a));
  for (char& ch : w) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return w;
}

// Calls f(line, n) for each line of `block` (n from 1) until f returns true; true if one did.
template <class F>
bool any_line(std::string_view block, F f) {
  int n = 0;
  for (std::size_t p = 0; p < block.size();) {
    const std::size_t e = std::min(block.find('\n', p), block.size());
    if (f(block.substr(p, e - p), ++n)) return true;
    p = e + 1;
  }
  return false;
}

// Does `block` hold `word` as a command? (A comment that mentions M190 is not one.)
bool has_command(std::string_view block, std::string_view word) {
  return any_line(block, [&](std::string_view l, int) { return command_of(l) == word; });
}

// The first placeholder or macro left in `block` outside comments, e.g. "{max_layer_z}" or
// "[printer_model]"; "" when none.
std::string leftover_placeholder(std::string_view block) {
  std::string found;
  any_line(block, [&](std::string_view l, int) {
    l = l.substr(0, l.find(';'));
    for (const auto& [open, close] : {std::pair{'{', '}'}, std::pair{'[', ']'}})
      if (const auto a = l.find(open); a != std::string_view::npos) {
        const auto b = l.find(close, a);
        found = l.substr(a, b == std::string_view::npos ? l.npos : b - a + 1);
        return true;
      }
    return false;
  });
  return found;
}

// The first line of `block` a firmware cannot take as written: longer than 255 characters
// (Marlin reads 96), or with a control byte anywhere or a non-ASCII byte outside the
// comment (the settings fuzzer sent binary through end_gcode). "" when all are fine.
std::string unprintable_line(std::string_view block) {
  std::string why;
  any_line(block, [&](std::string_view l, int n) {
    if (l.size() > 255)
      return why = "line " + std::to_string(n) + " is longer than 255 characters", true;
    const std::size_t semi = std::min(l.find(';'), l.size());
    for (std::size_t i = 0; i < l.size(); ++i) {
      const auto b = static_cast<unsigned char>(l[i]);
      if ((b < 0x20 && b != '\t' && b != '\r') || b == 0x7f || (b >= 0x80 && i < semi))
        return why = "line " + std::to_string(n) + " holds a byte that is not printable ASCII",
               true;
    }
    return false;
  });
  return why;
}

bool on_bed(const Vec3& p, const PrintConfig& c, double margin = 0) {
  const double eps = 1e-3 + margin;  // what %.3f may round
  return p.x() >= c.bed_min.x() - eps && p.x() <= c.bed_max.x() + eps &&
         p.y() >= c.bed_min.y() - eps && p.y() <= c.bed_max.y() + eps;
}

std::string bed_text(const PrintConfig& c) {
  char buf[120];
  std::snprintf(buf, sizeof buf, "the bed is X %g to %g, Y %g to %g", c.bed_min.x(), c.bed_max.x(),
                c.bed_min.y(), c.bed_max.y());
  return buf;
}

// Moves of a custom block that go off the bed. `prefix` sets the position it starts from.
std::optional<Error> check_block_on_bed(const std::string& key, const std::string& block,
                                        const std::string& prefix, const PrintConfig& c) {
  const std::string text = prefix + block;
  auto moves = read_gcode_moves(text);
  if (!moves) return Error{Status::invalid_argument, key + ": " + moves.error().message};
  const int skip = static_cast<int>(std::count(prefix.begin(), prefix.end(), '\n'));
  for (const PrintMove& m : *moves) {
    const bool moved_xy = (m.to.head<2>() - m.from.head<2>()).norm() > 0;
    // Printers travel a little past the bed's shape, and stock blocks use it: the MK3S's purge
    // line starts at Y-3. More than 5 mm off is a block written for another printer.
    if (!moved_xy || on_bed(m.to, c, 5.0)) continue;
    char buf[120];
    std::snprintf(buf, sizeof buf, ": line %d goes to X%.3f Y%.3f, off the bed; ", m.line - skip,
                  m.to.x(), m.to.y());
    return Error{Status::invalid_argument, key + buf + bed_text(c)};
  }
  return std::nullopt;
}

// The fan at `percent` as the flavour writes it.
std::string fan_line(int percent, GcodeFlavor flavor) {
  if (percent <= 0) return "M107";
  char buf[32];
  if (flavor == GcodeFlavor::reprapfirmware)
    std::snprintf(buf, sizeof buf, "M106 S%.2f", percent / 100.0);
  else
    std::snprintf(buf, sizeof buf, "M106 S%d", static_cast<int>(std::lround(2.55 * percent)));
  return buf;
}

// The built-in engine's layers as steps (program.hpp), written by the one writer: travels
// with retraction and lift, extrusions, and the bed check on every point. The nozzle's place
// and the retraction carry over from one layer to the next.
class LayerBuilder {
 public:
  explicit LayerBuilder(const PrintConfig& c)
      : c_(c), g_(c.gcode), tip_radius_(c.toolhead.tip_radius), printed_(c.bed_min, c.bed_max) {}
  /// The first point off the bed: the program is refused.
  std::optional<Error> fault;
  const char* what = "the print";  ///< what is being built, for the fault's message
  ProgramLayer layer;              ///< the layer being built

  void reset_e() {
    if (!g_.relative_e) layer.e_reset("G92 E0", 0);
  }
  void retract() {
    if (retracted_ || g_.retract_length <= 0) return;
    move_e(-g_.retract_length, g_.retract_speed, "retract");
    retracted_ = true;
  }
  void unretract() {
    if (!retracted_) return;
    move_e(g_.retract_length, g_.deretract_speed > 0 ? g_.deretract_speed : g_.retract_speed,
           "unretract");
    retracted_ = false;
  }
  // Travel to p: lift and retract for long moves, never through the part at print height.
  // On a curved layer, as travel_height says (toolhead.hpp). (Travelling at the ends' height
  // went 0.12 mm under a neighbouring line on a wave; TravelsClearPrintedMaterial found it.)
  void travel(const Vec3& p, double speed, bool curved, double safe_z, double slope) {
    check_on_bed(p, what);  // a travel to the skirt is the skirt's problem
    const double f = feed(speed);
    // Over what was laid before along the way, where that stands higher than this layer (a
    // shell's piece printed after core layers that rise above it: the bunny's went through
    // them at the piece's own height + 0.3 mm).
    if (have_pos_) {
      const double clear =
          printed_.to_clear(pos_, p, tip_radius_ + program::kTravelCorridor, safe_z);
      if (clear > std::max({safe_z, p.z(), pos_.z()})) curved = true, safe_z = clear;
    }
    if (curved && have_pos_) {
      const double d = (p.head<2>() - pos_.head<2>()).norm();
      if (d < 1e-6 && std::abs(p.z() - pos_.z()) < 1e-6) return;
      const double lift =
          travel_height(pos_, p, safe_z, slope, tip_radius_, travel_lift(g_.retract_lift));
      if (!std::isnan(lift)) {
        if (d > g_.retract_before_travel) retract();
        layer.lifted_travel(pos_, p, lift, f, f);
        pos_ = p;
        return;
      }
    }
    const double d = (p.head<2>() - pos_.head<2>()).norm();
    if (!have_pos_) {
      // Wherever the start G-code left the nozzle, the way to the print is long: retract.
      retract();
      layer.start(ProgramStep::Kind::travel);
      z_to(p, f), xy_to(p, f);
      pos_ = p, have_pos_ = true;
      return;
    }
    if (d < 1e-6 && std::abs(p.z() - pos_.z()) < 1e-6) return;
    const bool long_move = d > g_.retract_before_travel;
    if (long_move) retract();
    layer.start(ProgramStep::Kind::travel);
    if (long_move && g_.retract_lift > 0)
      z_to(Vec3(p.x(), p.y(), std::max(pos_.z(), p.z()) + g_.retract_lift), f);
    else if (p.z() > pos_.z() + 1e-9)
      z_to(p, f);
    xy_to(p, f);
    if ((long_move && g_.retract_lift > 0) || p.z() < pos_.z() - 1e-9) z_to(p, f);
    pos_ = p;
  }
  /// The next extrude() calls draw one path of this role and width.
  void begin_path(ExtrusionRole role, double width) { role_ = role, width_ = width, fresh_ = true; }
  void extrude(const Vec3& p, double de, double speed, double height) {
    check_on_bed(p, what);
    unretract();
    const bool begins =
        fresh_ || layer.steps.empty() || layer.steps.back().kind != ProgramStep::Kind::extrusion;
    if (begins) layer.start(ProgramStep::Kind::extrusion, role_, width_), fresh_ = false;
    // F is modal: written where a path's moves begin and where the speed changes, as
    // PrusaSlicer does (on every move it was 4.3 MB of the bunny's 37 MB).
    const double f = feed(speed);
    ProgramMove m;
    m.to = p, m.xy = true, m.z = std::abs(p.z() - pos_.z()) > 1e-9, m.de = de;
    m.f = begins || f != path_f_ ? f : kNoValue;
    path_f_ = f;
    m.height = height;
    layer.move(m);
    printed_.lay(pos_, p);
    pos_ = p;
  }

 private:
  // Feed rates are written as whole mm/min, truncated as they always were.
  static double feed(double mm_per_s) { return static_cast<int>(mm_per_s * 60); }
  void z_to(const Vec3& p, double f) {
    ProgramMove m;
    m.to = p, m.z = true, m.f = f;
    layer.move(m);
  }
  void xy_to(const Vec3& p, double f) {
    ProgramMove m;
    m.to = p, m.xy = true, m.f = f;
    layer.move(m);
  }
  void move_e(double de, double speed, const char* why) {
    layer.start(ProgramStep::Kind::retract);
    ProgramMove m;
    m.to = pos_, m.de = de, m.f = feed(speed), m.comment = why;
    layer.move(m);
  }
  void check_on_bed(const Vec3& p, const char* kind) {
    if (fault || on_bed(p, c_)) return;
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s reaches X%.3f Y%.3f, off the bed; ", kind, p.x(), p.y());
    fault = Error{Status::invalid_argument,
                  buf + bed_text(c_) + " (move the part, or use fewer skirts or a smaller " +
                      "skirt_distance)"};
  }
  const PrintConfig& c_;
  const GcodeParams& g_;
  double tip_radius_;  ///< what a short hop must clear (travel_height)
  program::PrintedTop printed_;
  Vec3 pos_ = Vec3::Zero();
  bool have_pos_ = false, retracted_ = false;
  ExtrusionRole role_ = ExtrusionRole::perimeter;
  double width_ = 0;
  bool fresh_ = false;  ///< begin_path was called and nothing extruded since
  double path_f_ = 0;   ///< the feed rate of the extrusion step's last move
};

}  // namespace

namespace {

// The custom blocks of one print, expanded for it.
struct Blocks {
  std::string start, end, start_filament, end_filament;
};

// What makes an expanded block unfit to send: a line a printer cannot take, a placeholder
// left unexpanded, an E mode against use_relative_e_distances (a block's M83 under absolute E
// would make every later E value a huge extrusion), or a line the one reader refuses.
std::optional<Error> block_fault(const std::string& key, const std::string& block,
                                 bool relative_e) {
  if (const std::string bad = unprintable_line(block); !bad.empty())
    return Error{Status::invalid_argument, key + ": " + bad};
  const std::string left = leftover_placeholder(block);
  if (!left.empty())
    return Error{Status::invalid_argument, key + ": " + left +
                                               " is not a placeholder this writer knows; edit it "
                                               "out, or slice with --engine prusaslicer"};
  if (has_command(block, relative_e ? "M82" : "M83"))
    return Error{Status::invalid_argument,
                 key + ": sets " + (relative_e ? "absolute" : "relative") + " extrusion (" +
                     (relative_e ? "M82" : "M83") + ") but use_relative_e_distances is " +
                     (relative_e ? "1" : "0")};
  if (auto moves = read_gcode_moves(block); !moves)
    return Error{Status::invalid_argument, key + ": " + moves.error().message};
  return std::nullopt;
}

// Expands start, end and filament blocks with the print's facts and checks what a printer
// would be sent: printable lines, nothing left unexpanded, moves on the bed, and an E mode
// that agrees with use_relative_e_distances (a block's M83 under absolute E would make every
// later E value a huge extrusion).
Expected<Blocks> expand_blocks(const PrintConfig& c, const PrintFacts& f) {
  MacroVariables v = block_variables(c, f);
  Blocks b;
  auto one = [&](std::string& out, const std::string& text, const char* key) -> Expected<void> {
    auto e = expand(text, v, key);
    if (!e) return e.error();
    out = std::move(*e);
    return {};
  };
  const GcodeParams& g = c.gcode;
  if (auto e = one(b.start, g.start_gcode, "start_gcode"); !e) return e.error();
  if (auto e = one(b.start_filament, g.start_filament_gcode, "start_filament_gcode"); !e)
    return e.error();
  v.set("layer_num", MacroValue::integer(std::max(0, f.layers - 1)));
  if (auto e = one(b.end_filament, g.end_filament_gcode, "end_filament_gcode"); !e)
    return e.error();
  if (auto e = one(b.end, g.end_gcode, "end_gcode"); !e) return e.error();
  for (const auto& [key, block] : {std::pair{"start_gcode", &b.start},
                                   {"end_gcode", &b.end},
                                   {"start_filament_gcode", &b.start_filament},
                                   {"end_filament_gcode", &b.end_filament}})
    if (auto e = block_fault(key, *block, g.relative_e)) return *e;
  // Every block is read by the one reader, so a line it refuses is named by its block here,
  // not found later in the print.
  if (auto e = check_block_on_bed("start_gcode", b.start, "", c)) return *e;
  if (auto e = check_block_on_bed("start_filament_gcode", b.start_filament, "", c)) return *e;
  char at[80];  // the end blocks start over the print, somewhere on the bed
  std::snprintf(at, sizeof at, "G92 X%g Y%g Z%g\n", 0.5 * (f.first_min.x() + f.first_max.x()),
                0.5 * (f.first_min.y() + f.first_max.y()), f.max_layer_z);
  if (auto e = check_block_on_bed("end_filament_gcode", b.end_filament, at, c)) return *e;
  if (auto e = check_block_on_bed("end_gcode", b.end, at, c)) return *e;
  return b;
}

// before_layer_gcode / layer_gcode for layer i (layer_num from 0, as PrusaSlicer).
Expected<std::string> layer_block(const std::string& text, const char* key, MacroVariables& v,
                                  std::size_t i, const LayerToolpaths& L, double& max_z,
                                  bool relative_e) {
  if (text.empty()) return std::string();
  max_z = std::max({max_z, L.z, L.max_z});
  v.set("layer_num", MacroValue::integer(static_cast<long long>(i)));
  v.set("layer_z", MacroValue::real(L.z));
  v.set("max_layer_z", MacroValue::real(max_z));
  auto e = expand(text, v, key);
  if (!e) return Error{e.error().status, e.error().message + " (layer " + std::to_string(i) + ")"};
  if (auto bad = block_fault(key, *e, relative_e))
    return Error{bad->status, bad->message + " (layer " + std::to_string(i) + ")"};
  return e;
}

}  // namespace

namespace {

// The start block: our header, temperatures, modes, object labels, the start G-code.
void write_start(program::GcodeText& w, const PrintConfig& c, const Blocks& blocks,
                 const std::vector<std::string>& header, const std::string& labels) {
  const GcodeParams& g = c.gcode;
  w.raw("; generated by nonplanar 0.1.0");
  for (const auto& h : header) w.raw(";" + (" " + h));
  w.line(";FLAVOR:%s", flavor_name(g.flavor));
  w.line("M140 S%g", g.first_layer_bed_temperature);
  w.line("M104 S%g", g.first_layer_temperature);
  if (!has_command(blocks.start, "M190")) w.line("M190 S%g", g.first_layer_bed_temperature);
  if (!has_command(blocks.start, "M109")) w.line("M109 S%g", g.first_layer_temperature);
  w.raw("G21 ; millimetres");
  w.raw("G90 ; absolute XYZ");
  w.raw(g.relative_e ? "M83 ; relative E" : "M82 ; absolute E");
  w.block(labels);
  // The start and end G-code are "Custom" moves, as PrusaSlicer marks them: its viewer shows
  // the purge line so, and the reader's print ends at the last one.
  w.raw(";TYPE:Custom");
  w.block(blocks.start);
  w.block(blocks.start_filament);
  w.raw("G92 E0");
}

// Layer i's paths as steps (em.layer, after its custom blocks): each path travelled to, then
// extruded, inside its object's label. Returns the filament pushed, mm.
double build_paths(LayerBuilder& em, const LayerToolpaths& L, const PrintConfig& c,
                   const gcode::ObjectLabels& labels) {
  ProgramLayer& out = em.layer;
  ExtrusionRole role = ExtrusionRole::skirt;
  double width = -1, filament = 0;
  bool first = true;
  int labelled = -1;  // the object whose label this layer is inside (-1: none)
  for (const ExtrusionPath& p : L.paths) {
    if (p.points.size() < 2) continue;
    if (labelled != p.object && p.role != ExtrusionRole::skirt) {
      if (labelled >= 0) out.block(labels.stop(labelled));
      out.block(labels.start(p.object)), labelled = p.object;
    }
    em.what = p.role == ExtrusionRole::skirt ? "the skirt" : "the print";
    em.travel(program::on_file_grid(p.points.front()), c.paths.travel_speed, L.nonplanar, L.max_z,
              L.max_slope);
    if (first || p.role != role) out.line(";TYPE:%s", role_name(p.role));
    if (first || std::abs(p.width - width) > 1e-9) out.line(";WIDTH:%.3f", p.width);
    first = false;
    role = p.role, width = p.width;
    em.begin_path(p.role, p.width);
    // Points as the file holds them: E follows the length written.
    Vec3 from = program::on_file_grid(p.points.front());
    for (std::size_t k = 1; k < p.points.size(); ++k) {
      const Vec3 to = program::on_file_grid(p.points[k]);
      const double len = (to - from).norm();
      if (len < 1e-6) continue;
      // Each segment's own height sets its extrusion (non-planar paths vary).
      const double h = 0.5 * (p.height[k] + p.height[k - 1]);
      const double de = len * filament_per_mm(p.width, h, c.gcode);
      filament += de;
      em.extrude(to, de, p.speed, p.height[k]);
      from = to;
    }
  }
  if (labelled >= 0) out.block(labels.stop(labelled));
  em.retract();
  return filament;
}

}  // namespace

Expected<std::string> make_gcode(const std::vector<LayerToolpaths>& layers, const PrintConfig& c,
                                 const std::vector<std::string>& header, const Context& ctx) {
  ctx.progress("gcode", 0);
  const GcodeParams& g = c.gcode;
  const PrintFacts facts = facts_of(layers, c);
  auto blocks = expand_blocks(c, facts);
  if (!blocks) return blocks.error();
  MacroVariables layer_vars = block_variables(c, facts);
  double max_z = 0;
  program::GcodeText w(g.relative_e);
  // Room made once and backed by huge pages (a text grown by doubling faulted each new buffer
  // in 4 KiB at a time), and more than it needs: 39-43.5 bytes a point were measured (a move's
  // line, a path's travel a few lines), and pages never written are never resident. At 32 a
  // point the bunny's shells (37 MB of text) ran out at 28.5 MB and were copied into 57 MB.
  std::size_t points = 0, paths = 0;
  for (const LayerToolpaths& L : layers) {
    paths += L.paths.size();
    for (const ExtrusionPath& p : L.paths) points += p.points.size();
  }
  w.out.reserve((std::size_t(1) << 20) + 48 * points + 160 * paths);
  advise_huge_pages(w.out.data(), w.out.capacity());
  const gcode::ObjectLabels labels = gcode::object_labels(c);
  write_start(w, c, *blocks, header, labels.define(layers));
  // The layers, one at a time as steps.
  LayerBuilder em(c);
  ProgramLayer& out = em.layer;
  double filament = 0;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    const LayerToolpaths& L = layers[i];
    out.clear();
    out.raw(";LAYER_CHANGE");
    out.z_comment(L.z);
    out.height_comment(L.height);
    auto before = layer_block(g.before_layer_gcode, "before_layer_gcode", layer_vars, i, L, max_z,
                              g.relative_e);
    if (!before) return before.error();
    out.block(*before);
    em.reset_e();
    auto after = layer_block(g.layer_gcode, "layer_gcode", layer_vars, i, L, max_z, g.relative_e);
    if (!after) return after.error();
    out.block(*after);
    if (i == 1) {
      if (g.temperature != g.first_layer_temperature) out.line("M104 S%g", g.temperature);
      if (g.bed_temperature != g.first_layer_bed_temperature)
        out.line("M140 S%g", g.bed_temperature);
    }
    if (static_cast<int>(i) == g.disable_fan_first_layers) out.raw(fan_line(g.fan_speed, g.flavor));
    filament += build_paths(em, L, c, labels);
    program::write_program_layer(w, out);
    ctx.progress("gcode", static_cast<double>(i + 1) / static_cast<double>(layers.size()));
  }
  if (em.fault) return *em.fault;
  if (w.fault) return *w.fault;
  // The end block.
  w.raw(";TYPE:Custom");
  w.raw(fan_line(0, g.flavor));
  w.block(blocks->end_filament);
  w.block(blocks->end);
  w.line("; filament used [mm] = %.2f", filament);
  w.line("; filament used [cm3] = %.3f",
         filament * M_PI * 0.25 * g.filament_diameter * g.filament_diameter / 1000.0);
  if (w.fault) return *w.fault;
  return std::move(w.out);
}

Expected<void> check_custom_gcode(const PrintConfig& c) {
  // Before slicing: the footprint is not known yet, so the blocks see the bed's centre and a
  // 10 mm part; make_gcode expands them again with the print's own facts.
  PrintFacts f;
  f.first_min = f.first_max = c.bed_center();
  f.max_layer_z = 10;
  f.layers = 1;
  auto b = expand_blocks(c, f);
  if (!b) return b.error();
  MacroVariables v = block_variables(c, f);
  LayerToolpaths first;
  first.z = first.max_z = c.slice.first_layer_height;
  double max_z = 0;
  for (const auto& [key, text] : {std::pair{"before_layer_gcode", &c.gcode.before_layer_gcode},
                                  {"layer_gcode", &c.gcode.layer_gcode}})
    if (auto e = layer_block(*text, key, v, 0, first, max_z, c.gcode.relative_e); !e)
      return e.error();
  return {};
}

Expected<void> write_gcode_file(const std::filesystem::path& file,
                                const std::vector<LayerToolpaths>& layers, const PrintConfig& c,
                                const std::vector<std::string>& header, const Context& ctx) {
  auto text = make_gcode(layers, c, header, ctx);
  if (!text) return text.error();
  return write_gcode_text(file, *text, ctx);
}

Expected<void> write_gcode_text(const std::filesystem::path& file, const std::string& gcode,
                                const Context& ctx) {
  const std::string* text = &gcode;
  // Cancelled while writing: the writer removes its temporary, and no file appears.
  auto w = write_file_atomically(file, [&](std::ostream& out) {
    out.write(text->data(), static_cast<std::streamsize>(text->size()));
    return bool(out) && !ctx.cancelled();
  });
  if (!w && ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  return w;
}

}  // namespace nonplanar
