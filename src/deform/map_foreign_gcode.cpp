// Mapping another slicer's planar G-code of the normalised mesh back onto the curved layers
// (issue: libslic3r engine). Notation as in map_segment.hpp; E is filament length (mm).
//
// The file is read by the one reader (program.hpp), a piece at a time (GcodePieceReader: the
// start, a window of layers, the end), and keeps its own program: start and end G-code,
// temperatures, fan, speeds and retractions pass untouched. Inside the print (first
// ;LAYER_CHANGE to the ;TYPE:Custom that follows the last typed extrusion), a layer at a time:
// its extrusions are cut back under a shell if asked (clip_layer), mapped like the built-in
// engine's paths (resampled, each piece's E scaled by its own 3D length and layer thickness
// against the planar ones, L·t / (L_p·h)), a wipe follows the layer with its E spread over
// the pieces, top skins are re-ordered low to high (order_top_skins), and a travel over
// curved layers rises above the layer's highest point (or, for a hop under 0.6 mm, its
// slope's reach) and comes down at the target, as the built-in writer does. Each layer is
// built as steps (ProgramLayer) and written by the one writer; the result is three blocks,
// start, print and end, which the shell route joins. Paths another stage made (a shell's
// pieces where the part stands above it) can be written between the file's layers.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "core/huge_pages.hpp"
#include "core/parallel.hpp"
#include "deform/map_gcode_layer.hpp"
#include "deform/map_segment.hpp"
#include "nonplanar/deform.hpp"
#include "program/gcode_text.hpp"
#include "program/layer_passes.hpp"
#include "program/printed_top.hpp"

namespace nonplanar {
namespace {

using Kind = GcodeLine::Kind;
using program::GcodeText;
using program::LayerWork;

// What carries over from one layer's writing to the next.
struct Writing {
  Writing(GcodeText text, program::PrintedTop top) : w(std::move(text)), printed(std::move(top)) {}
  GcodeText w;
  ProgramLayer layer{};         ///< the layer being built (then written into w)
  Vec3 at{0, 0, 0};             ///< the nozzle, mapped
  double pending = 0;           ///< filament owed from before the print, given back at the first E
  double retracted = 0;         ///< filament the print's own retractions leave pulled back
  program::PrintedTop printed;  ///< what the travels must clear (mapped extrusions so far)
  /// After inserted paths (ForeignMapOptions::before_layer): the top of what they laid, which
  /// the nozzle waits over until the file's next move in X or Y (NaN: not waiting).
  double hover = std::numeric_limits<double>::quiet_NaN();
};

// An extrusion or wipe (a travel step, retracting as it goes), one G1 per mapped piece; an
// extrusion also goes into the gate's path (L.paths[*run], started when *run < 0). Adds the
// layer thicknesses written to h_sum, h_n.
void add_pieces(const GcodeMove& m, const ExtrusionPath& p, LayerToolpaths& L, long& run,
                Writing& s, double& h_sum, std::size_t& h_n) {
  const double lp = (m.to - m.from).norm();
  double l3 = 0;
  for (std::size_t q = 1; q < p.points.size(); ++q) l3 += (p.points[q] - p.points[q - 1]).norm();
  double f = m.f;
  if (!std::isnan(s.hover)) {  // waiting over inserted paths: down to this one's start
    s.layer.lifted_travel(s.at, p.points[0], s.at.z(), kNoValue, kNoValue);
    s.at = p.points[0], s.hover = std::numeric_limits<double>::quiet_NaN();
  }
  if (s.pending != 0 && m.has_e) {
    s.layer.start(ProgramStep::Kind::retract);
    s.layer.move_from(s.at, s.at, s.pending, kNoValue), s.pending = 0;
  }
  if (!m.extruding() && m.has_e) s.retracted -= m.de;
  if (m.extruding() && (run < 0 || L.paths[static_cast<std::size_t>(run)].object != p.object)) {
    ExtrusionPath g;
    g.role = role_from_name(m.type), g.width = m.width, g.object = p.object;
    g.points.push_back(p.points[0]);
    g.height.push_back(p.height[0]);
    L.paths.push_back(std::move(g));
    run = static_cast<long>(L.paths.size()) - 1;
  }
  s.layer.start(m.extruding() ? ProgramStep::Kind::extrusion : ProgramStep::Kind::travel,
                role_from_name(m.type), m.width);
  for (std::size_t q = 1; q < p.points.size(); ++q) {
    const double seg = (p.points[q] - p.points[q - 1]).norm();
    double de;
    if (m.extruding()) {
      const double hq = 0.5 * (p.height[q] + p.height[q - 1]);
      de = lp > 0 ? m.de * (seg / lp) * (hq / m.height) : 0;
      ExtrusionPath& g = L.paths[static_cast<std::size_t>(run)];
      s.printed.lay(p.points[q - 1], p.points[q]);
      g.points.push_back(p.points[q]);
      g.height.push_back(p.height[q]);
      h_sum += p.height[q], ++h_n;
    } else {
      de = l3 > 0 ? m.de * seg / l3 : 0;
    }
    s.layer.move_from(s.at, p.points[q], m.has_e ? de : kNoValue, f,
                      m.extruding() ? p.height[q] : 0);
    f = kNoValue;
    s.at = p.points[q];
  }
  if (!m.extruding()) run = -1;
}

// A retraction, or a travel (or a Z move) to the target's place on its layer, lifted over
// curved layers. A Z move stays where the nozzle is (not where the file's start G-code left
// it, when the caller moved the start).
void add_travel(const GcodeMove& m, const LayerField& field, const MapBackParams& params,
                const LayerToolpaths& L, bool keep, Writing& s) {
  if (!m.has_xy && !m.has_z) {  // retraction, F only
    if (m.has_e) s.retracted -= m.de;
    s.layer.start(ProgramStep::Kind::retract);
    s.layer.move_from(s.at, s.at, m.has_e ? m.de + s.pending : kNoValue, m.f);
    if (m.has_e) s.pending = 0;
    return;
  }
  const Vec3 planar_to = m.has_xy ? m.to : Vec3(s.at.x(), s.at.y(), m.to.z());
  const Mapped target = keep ? Mapped{planar_to, m.height} : map_point(field, planar_to, m.height);
  Vec3 to = target.p;
  bool curved =
      target.p.z() != m.to.z() || !field.planar_at(m.from.x(), m.from.y()) ||
      !field.planar_along(m.from.head<2>(), m.to.head<2>(), field.t_of_zeta(m.to.z() - m.height),
                          field.t_of_zeta(m.to.z()));
  const bool hovering = !std::isnan(s.hover);
  if (hovering && !m.has_xy) to.z() = std::max(to.z(), s.at.z());  // a layer change: still over
  if (hovering && m.has_xy) curved = true;
  // Over what was printed before along the way where it stands higher than this layer (a
  // planar object's layer after a curved layer of the planned part that rose above it: the
  // dome beside a cube was crossed at the cube's height + 0.3 mm, 0.4 mm under its top).
  double top = L.max_z;
  if (hovering && m.has_xy) top = std::max(top, s.hover), s.hover = std::nan("");
  if (m.has_xy) {
    const double clear =
        s.printed.to_clear(s.at, to, params.tip_radius + program::kTravelCorridor, top);
    if (clear > std::max({top, s.at.z(), to.z()})) top = clear, curved = true;
  }
  const double de = m.has_e ? m.de + s.pending : kNoValue;
  if (m.has_e) s.retracted -= m.de, s.pending = 0;
  const double lift = curved && m.has_xy ? travel_height(s.at, to, top, L.max_slope,
                                                         params.tip_radius, params.travel_lift)
                                         : kNoValue;
  if (!std::isnan(lift)) {
    s.layer.lifted_travel(s.at, to, lift, m.f, kNoValue, de);
  } else {
    s.layer.start(ProgramStep::Kind::travel);
    s.layer.move_from(s.at, to, de, m.f);
  }
  s.at = to;
}

// Paths printed between the file's layers (ForeignMapOptions::before_layer), as the built-in
// writer prints its own: each piece a layer, each path travelled to lifted over what is
// printed, pulled back by the file's retraction on the way and given it back there, then
// extruded by the printer's filament model at each point's height. After the last the filament
// stays pulled back (owed to the file's next E, so that its own retractions balance as it wrote
// them) and the nozzle waits lifted where it ended: the file's next layer change would lower it
// into them there.
void write_inserted(std::vector<LayerToolpaths>& pieces, const GcodeRetraction& r,
                    const MapBackParams& params, const ForeignMapOptions& o, Writing& s) {
  const double travel_f = 60 * o.inserted_travel_speed;
  const double pull_f = std::isnan(r.f) ? travel_f : r.f;
  const double back_f = std::isnan(r.back_f) ? pull_f : r.back_f;
  if (std::none_of(pieces.begin(), pieces.end(), [](const LayerToolpaths& L) {
        return std::any_of(L.paths.begin(), L.paths.end(),
                           [](const ExtrusionPath& p) { return p.points.size() >= 2; });
      }))
    return;
  double back = s.retracted + s.pending;  // filament pulled back now, mm
  auto pull_to = [&](double to) {
    if (std::abs(to - back) < 1e-9) return;
    s.layer.start(ProgramStep::Kind::retract);
    s.layer.move_from(s.at, s.at, back - to, to > back ? pull_f : back_f);
    back = to;
  };
  s.layer.clear();
  s.layer.raw("; nonplanar: curved paths printed between the engine's layers");
  double laid = std::isnan(s.hover) ? -std::numeric_limits<double>::infinity() : s.hover;
  for (LayerToolpaths& L : pieces) {
    // A layer of its own, as the built-in engine writes a piece: a viewer or a checker reads
    // the layer's points together (a plane through them at a point, its highest layer there).
    s.layer.raw(";LAYER_CHANGE");
    s.layer.z_comment(L.z);
    s.layer.height_comment(L.height);
    ExtrusionRole role = ExtrusionRole::skirt;
    double width = -1;
    for (const ExtrusionPath& p : L.paths) {
      if (p.points.size() < 2) continue;
      const Vec3& to = p.points.front();
      if ((to - s.at).head<2>().norm() > 1e-6 || std::abs(to.z() - s.at.z()) > 1e-6) {
        pull_to(std::max(r.length, 0.0));
        double top = std::max({L.max_z, laid, s.at.z(), to.z()});
        top = s.printed.to_clear(s.at, to, params.tip_radius + program::kTravelCorridor, top);
        const double lift = travel_height(s.at, to, top, std::max(L.max_slope, 1.0),
                                          params.tip_radius, params.travel_lift);
        if (std::isnan(lift)) {
          s.layer.start(ProgramStep::Kind::travel);
          s.layer.move_from(s.at, to, kNoValue, travel_f);
        } else {
          s.layer.lifted_travel(s.at, to, std::max(lift, s.at.z()), travel_f, travel_f);
        }
        s.at = to;
      }
      pull_to(0);
      if (p.role != role) s.layer.line(";TYPE:%s", role_name(p.role));
      if (std::abs(p.width - width) > 1e-9) s.layer.line(";WIDTH:%.3f", p.width);
      role = p.role, width = p.width;
      s.layer.start(ProgramStep::Kind::extrusion, p.role, p.width);
      double f = 60 * p.speed;
      for (std::size_t k = 1; k < p.points.size(); ++k) {
        const Vec3& q = p.points[k];
        const double de =
            (q - s.at).norm() * o.filament_per_mm(p.width, 0.5 * (p.height[k] + p.height[k - 1]));
        s.layer.move_from(s.at, q, de, f, p.height[k]);
        f = kNoValue;
        s.printed.lay(s.at, q);
        laid = std::max(laid, q.z());
        s.at = q;
      }
    }
  }
  pull_to(std::max(r.length, back));
  const Vec3 over(s.at.x(), s.at.y(), std::max(s.at.z(), laid) + params.travel_lift);
  s.layer.start(ProgramStep::Kind::travel);
  s.layer.move_from(s.at, over, kNoValue, travel_f);
  s.at = over, s.hover = laid;
  s.pending = back - s.retracted;
  program::write_program_layer(s.w, s.layer);
}

// One mapped layer as steps (s.layer); ;Z: becomes its highest point and ;HEIGHT: its mean
// thickness (planar_h when it extrudes nothing).
void build_layer(const LayerWork& work, const LayerField& field, const MapBackParams& params,
                 const std::vector<char>& planar_lines, double planar_h, LayerToolpaths& L,
                 Writing& s) {
  double h_sum = 0;
  std::size_t h_n = 0;
  long run = -1;                              // the gate's path being extended
  std::vector<std::size_t> z_steps, h_steps;  // filled in once the layer is mapped
  for (const GcodeLine& it : work.lines) {
    switch (it.kind) {
      case Kind::xyz_relative:  // mapped moves are written absolute: the printer stays in G90
        s.layer.raw("; G91 (relative XYZ) applied by nonplanar: the mapped moves are absolute");
        continue;
      case Kind::text:
        s.layer.raw(it.raw);
        continue;
      case Kind::e_reset:
        s.layer.e_reset(it.raw, it.value);
        continue;
      case Kind::e_mode:
        s.layer.e_mode(it.raw, it.value != 0);
        continue;
      case Kind::z_comment:
        z_steps.push_back(s.layer.z_comment(0));
        continue;
      case Kind::height_comment:
        h_steps.push_back(s.layer.height_comment(0));
        continue;
      case Kind::move:
        break;
    }
    const GcodeMove& m = work.moves[static_cast<std::size_t>(it.move)];
    const ExtrusionPath& p = work.mapped[static_cast<std::size_t>(it.move)];
    if (!p.points.empty()) {
      add_pieces(m, p, L, run, s, h_sum, h_n);
      continue;
    }
    run = -1;
    add_travel(m, field, params, L, kept_planar(planar_lines, m), s);
  }
  for (const std::size_t k : z_steps) s.layer.steps[k].value = L.max_z;
  for (const std::size_t k : h_steps)
    s.layer.steps[k].value = h_n ? h_sum / static_cast<double>(h_n) : planar_h;
  L.z = L.max_z;
  L.height = planar_h;
  L.nonplanar = true;
}

// The file's first retraction in its print (none: length 0), read ahead up to it (its first
// layer, as a rule), so that a clip in the print's first piece retracts as in its last.
GcodeRetraction first_retraction(std::string_view text) {
  GcodePieceReader ahead(text);
  while (ahead.next(1) && !(ahead.program().retraction.length > 0)) {
  }
  return ahead.program().retraction;
}

// What the layers share while they are written in order.
struct InOrder {
  GcodeProgram& prog;
  program::MovePaths& mapped;
  const LayerField& field;
  const MapBackParams& params;
  const ForeignMapOptions& options;
  ForeignGcode& out;
  Writing& s;
  std::vector<char>& dropped;  ///< per layer: cut away whole
  /// The file's first retraction in its print: what its cut-away travels and the inserted
  /// paths' retract by.
  GcodeRetraction retraction;
  std::size_t clip_samples = 0, points = 0;
  /// Inserted paths (options.before_layer), each with the file's layer it went before.
  std::vector<std::pair<std::size_t, LayerToolpaths>> inserted{};
};

// What options.before_layer gives before the file's layer `layer` at `z` (+inf: after the
// last), written.
void insert_before(InOrder& o, std::size_t layer, double z) {
  if (!o.options.before_layer) return;
  std::vector<LayerToolpaths> pieces = o.options.before_layer(z, o.s.at);
  write_inserted(pieces, o.retraction, o.params, o.options, o.s);
  for (LayerToolpaths& L : pieces) o.inserted.emplace_back(layer, std::move(L));
}

// How much of the layer `span` the clip keeps (all without one). Another object's moves in the
// layer stay whatever the clip would do to the planned part's.
LayerClip::Cover layer_cover(const InOrder& o, const GcodeLayerSpan& span) {
  if (!o.options.clip) return LayerClip::Cover::all;
  const LayerClip::Cover cover = o.options.clip->cover(o.prog.layer_z[span.layer]);
  if (cover != LayerClip::Cover::none || o.options.planar_lines.empty()) return cover;
  for (std::size_t l = span.begin; l < span.end; ++l) {
    const GcodeLine& it = o.prog.lines[l];
    if (it.kind == Kind::move &&
        kept_planar(o.options.planar_lines, o.prog.moves[static_cast<std::size_t>(it.move)]))
      return LayerClip::Cover::some;
  }
  return cover;
}

// Where the clip cuts the layer `span` of cover `some`, its margins at the layer's z.
program::LayerCuts cut_layer(const InOrder& o, const GcodeLayerSpan& span,
                             std::atomic<std::size_t>& looked) {
  const std::vector<GcodeLine>& lines = o.prog.lines;
  std::vector<GcodeLine> seq(lines.begin() + static_cast<long>(span.begin),
                             lines.begin() + static_cast<long>(span.end));
  const LayerWork work{seq, o.prog.moves, o.mapped};
  const double z = o.prog.layer_z[span.layer];
  auto untouched = [&](const GcodeMove& m) { return kept_planar(o.options.planar_lines, m); };
  auto margin = [&](double x, double y) { return o.options.clip->margin(x, y, z); };
  auto bound = [&](const Vec2& lo, const Vec2& hi) {
    return o.options.clip->slope_bound(lo, hi, z);
  };
  return program::cut_layer(work, margin, bound, o.params.passes, looked, untouched);
}

// One layer: cut back under the shell (options.clip; where `cuts` says when it is complete),
// mapped (unless `premapped`, its point count from map_gcode_layers, says it is), top skins
// ordered, built as steps and written.
std::optional<Error> write_layer(InOrder& o, const GcodeLayerSpan& span,
                                 std::optional<std::size_t> premapped,
                                 const program::LayerCuts* cuts) {
  const std::vector<GcodeLine>& lines = o.prog.lines;
  std::vector<GcodeLine> seq(lines.begin() + static_cast<long>(span.begin),
                             lines.begin() + static_cast<long>(span.end));
  LayerWork work{seq, o.prog.moves, o.mapped};
  LayerToolpaths& L = o.out.layers[span.layer];
  const double z = o.prog.layer_z[span.layer];
  const LayerClip::Cover cover = layer_cover(o, span);
  auto untouched = [&](const GcodeMove& m) { return kept_planar(o.options.planar_lines, m); };
  o.s.layer.clear();
  if (cover == LayerClip::Cover::none) {
    program::dropped_layer(seq, o.s.layer);
    program::write_program_layer(o.s.w, o.s.layer);
    o.dropped[span.layer] = 1;
    return std::nullopt;
  }
  if (cover == LayerClip::Cover::some) {
    auto margin = [&](double x, double y) { return o.options.clip->margin(x, y, z); };
    auto bound = [&](const Vec2& lo, const Vec2& hi) {
      return o.options.clip->slope_bound(lo, hi, z);
    };
    const int bad = cuts && cuts->complete
                        ? program::clip_layer(work, *cuts, o.retraction, o.params.passes,
                                              o.clip_samples, untouched)
                        : program::clip_layer(work, margin, bound, o.retraction, o.params.passes,
                                              o.clip_samples, untouched);
    if (bad)
      return Error{Status::invalid_argument, "line " + std::to_string(bad) + ": more than " +
                                                 std::to_string(o.params.passes.most_clip_samples) +
                                                 " clip samples"};
  }
  if (premapped && *premapped != kFailed && o.points + *premapped <= o.params.most_points) {
    o.points += *premapped;
  } else {
    // Here, in order: so a file past most_points is refused at the line where the count
    // passes it, as when every layer is mapped in turn (what was mapped side by side goes).
    if (premapped)
      for (const GcodeLine& it : seq)
        if (it.kind == Kind::move) o.mapped[static_cast<std::size_t>(it.move)] = {};
    if (auto e = map_gcode_layer(seq, o.prog.moves, o.mapped, o.field, o.params,
                                 o.options.planar_lines, L, o.points))
      return e;
  }
  program::order_top_skins(work, o.params.passes);
  build_layer(work, o.field, o.params, o.options.planar_lines, o.prog.layer_height[span.layer], L,
              o.s);
  program::write_program_layer(o.s.w, o.s.layer);
  return std::nullopt;
}

// The layers of one piece of the print, mapped and written in order.
std::optional<Error> write_piece(InOrder& o, const Context& ctx) {
  GcodeProgram& prog = o.prog;
  const std::vector<GcodeLine>& lines = prog.lines;
  const std::vector<GcodeLayerSpan> spans = gcode_layer_spans(lines);
  o.mapped = program::MovePaths(prog.moves.size());
  o.mapped.window(0, prog.moves.size());
  // Nothing cut away: the layers are independent until their passes, and are mapped side by
  // side first (the bunny from PrusaSlicer, 1000 layers: map back 2.02 s -> 1.54 s), and a
  // layer's mapped moves go once it is written (they were all held at once: the bunny's map
  // back rose 200 MB over the rest of the slice's peak).
  std::vector<std::size_t> premapped;
  if (!o.options.clip)
    premapped = map_gcode_layers(lines, spans, prog.moves, o.mapped, o.field, o.params,
                                 o.options.planar_lines, o.out.layers, ctx);
  // With a clip, the layers are cut side by side first (its margins are most of the bunny's
  // core through PrusaSlicer: 0.5 s of CPU round its four shells), put together in order. A
  // layer cut short (the layers together went past the limit) is cut again in turn, which
  // finds the line the limit is passed on.
  std::vector<program::LayerCuts> cuts(o.options.clip ? spans.size() : 0);
  if (!cuts.empty()) {
    std::atomic<std::size_t> looked{o.clip_samples};
    core::parallel_for(std::size_t(0), spans.size(), [&](std::size_t k) {
      if (layer_cover(o, spans[k]) == LayerClip::Cover::some)
        cuts[k] = cut_layer(o, spans[k], looked);
    });
  }
  for (std::size_t k = 0; k < spans.size(); ++k) {
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    std::string& text = o.s.w.out;
    if (text.capacity() - text.size() < (std::size_t{1} << 20))
      reserve_text(text, 2 * text.capacity());
    insert_before(o, spans[k].layer, o.prog.layer_z[spans[k].layer]);
    if (auto e =
            write_layer(o, spans[k], premapped.empty() ? std::nullopt : std::optional(premapped[k]),
                        cuts.empty() ? nullptr : &cuts[k]))
      return e;
    if (!cuts.empty()) cuts[k] = {};
    for (std::size_t l = spans[k].begin; l < spans[k].end; ++l)
      if (lines[l].kind == Kind::move) o.mapped[static_cast<std::size_t>(lines[l].move)] = {};
  }
  return std::nullopt;
}

}  // namespace

std::string ForeignGcode::take_text(std::string_view head) {
  // In the print's own room (reserved twice the slicer's file, map_foreign_gcode) when the rest
  // fits there: a joined copy held the bunny's 28.6 MB twice at the engine route's peak.
  std::string t = std::move(print);
  if (t.capacity() - t.size() < head.size() + start.size() + end.size()) {
    t = joined_huge({head, start, t, end});
  } else {
    t.insert(0, std::string(head) + start);
    t += end;
  }
  start = std::string(), print = std::string(), end = std::string();
  return t;
}

namespace {

// map_foreign_gcode; `owned` (if given) is the text's own string, whose read pages may go.
Expected<ForeignGcode> map_text(std::string_view text, const LayerField& field,
                                const MapBackParams& params, const Context& ctx,
                                const ForeignMapOptions& options, std::string* owned) {
  if (!(params.tolerance > 0)) return Error{Status::invalid_argument, "map tolerance: must be > 0"};
  // Read a piece at a time: the start, a window of layers, the end. Held whole, the bunny's
  // lines and moves through PrusaSlicer were 118 MB of the engine route's peak (and through a
  // clip round its four shells, 365 MB against PrusaSlicer's 172).
  GcodePieceReader reader(text);
  GcodeProgram& prog = reader.program();
  if (reader.layer_count() == 0)
    return Error{Status::parse_error, "no ;LAYER_CHANGE: not a layered G-code file"};
  reader.next(0);  // the start
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};

  ForeignGcode out;
  Writing s(GcodeText(prog.at_print.relative_e, prog.at_print.e), program::PrintedTop());
  for (const GcodeLine& l : prog.lines) s.w.raw(l.raw);
  out.start = std::move(s.w.out);
  s.w.out.clear();
  out.relative_e_at_print = prog.at_print.relative_e, out.e_at_print = prog.at_print.e;
  out.fan_at_print = std::string(prog.fan_at_print);
  s.pending = options.start_retracted;
  std::vector<char> dropped;
  program::MovePaths mapped(0);
  // (Only a clip and inserted paths retract on their own.)
  const GcodeRetraction retraction =
      options.clip || options.before_layer ? first_retraction(text) : GcodeRetraction{};
  InOrder o{prog, mapped, field, params, options, out, s, dropped, retraction};
  const std::size_t window = std::max<std::size_t>(1, options.layers_at_once);
  bool placed = false, first = true;
  std::size_t released = 0;
  while (reader.next(window) && reader.piece() == GcodePieceReader::Piece::layers) {
    if (auto e = first_unmappable(prog)) return *e;
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    out.layers.resize(std::max(out.layers.size(), prog.layer_height.size()));
    dropped.resize(out.layers.size(), 0);
    // The print's text, mapped, in huge-page-advised room (grown by doubling, each larger
    // buffer's pages faulted in again, 4 KiB at a time): twice the slicer's to start with (the
    // bunny's 19 MB from PrusaSlicer map to 28.6 MB; a small part's curved layers, resampled,
    // to up to 13 times its file), then doubled before a layer when less than a MiB is left.
    if (first && !prog.lines.empty()) {
      const auto from = static_cast<std::size_t>(prog.lines[0].raw.data() - text.data());
      reserve_text(s.w.out, 2 * (text.size() - from) + 4096);
    }
    first = false;
    // The nozzle starts where the print's first move starts, or where the caller says.
    if (options.start && !placed) s.at = *options.start, placed = true;
    for (std::size_t l = 0; l < prog.lines.size() && !placed; ++l)
      if (prog.lines[l].kind == Kind::move)
        s.at = prog.moves[static_cast<std::size_t>(prog.lines[l].move)].from, placed = true;
    if (auto e = write_piece(o, ctx)) return *e;
    // What the reader has passed is never read again: its pages go as the map goes (the
    // bunny's core through PrusaSlicer: 174 MB at the engine route's peak, 156 without).
    if (owned) release_read_pages(*owned, reader.held_from(), released);
  }
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  insert_before(o, out.layers.size(), std::numeric_limits<double>::infinity());
  out.print = std::move(s.w.out);
  s.w.out.clear();
  out.end_at = s.at, out.retracted = s.retracted, out.relative_e_at_end = prog.at_end.relative_e;
  // The end G-code as written, after telling the firmware the file's own E (absolute E).
  if (!prog.lines.empty() && !prog.at_end.relative_e) s.w.line("G92 E%.5f", prog.at_end.e);
  if (!prog.lines.empty() && prog.at_end.relative_xyz) s.w.raw("G91 ; as the file had it here");
  for (const GcodeLine& l : prog.lines) s.w.raw(l.raw);
  if (s.w.fault) return *s.w.fault;
  out.end = std::move(s.w.out);
  // The gate's layers in print order: those cut away whole left out, the inserted ones where
  // they were written.
  std::vector<LayerToolpaths> layers;
  layers.reserve(out.layers.size() + o.inserted.size());
  auto ins = o.inserted.begin();
  for (std::size_t k = 0; k <= out.layers.size(); ++k) {
    for (; ins != o.inserted.end() && ins->first == k; ++ins) {
      if (out.inserted.empty()) out.inserted.assign(layers.size(), 0);
      layers.push_back(std::move(ins->second)), out.inserted.push_back(1);
    }
    if (k < out.layers.size() && !dropped[k]) {
      layers.push_back(std::move(out.layers[k]));
      if (!out.inserted.empty()) out.inserted.push_back(0);
    }
  }
  out.layers = std::move(layers);
  return out;
}

}  // namespace

Expected<ForeignGcode> map_foreign_gcode(std::string_view text, const LayerField& field,
                                         const MapBackParams& params, const Context& ctx,
                                         const ForeignMapOptions& options) {
  return map_text(text, field, params, ctx, options, nullptr);
}

Expected<ForeignGcode> map_foreign_gcode_consuming(std::string&& text, const LayerField& field,
                                                   const MapBackParams& params, const Context& ctx,
                                                   const ForeignMapOptions& options) {
  std::string own = std::move(text);
  return map_text(own, field, params, ctx, options, &own);
}

}  // namespace nonplanar
