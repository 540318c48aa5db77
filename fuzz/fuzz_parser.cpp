// One libFuzzer target per parser: this file is compiled once per parser with
// NONPLANAR_FUZZ_PARSER set to its number (see fuzz/CMakeLists.txt). Every parser must return
// an Error for bad input; a crash, hang, leak or sanitizer report is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/readers.hpp"
#include "layers/shell_plan.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/field_io.hpp"
#include "nonplanar/macros.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/surface_io.hpp"
#include "nonplanar/toolhead.hpp"

#if NONPLANAR_FUZZ_PARSER == 8
#include <cmath>
#include <string>
#include <vector>

#include "nonplanar/program.hpp"
#include "program/splice_lines.hpp"
namespace {
// Layers 0.2 mm thick at x = 0, thicker and thinner along x (every column curved), so the
// mapper resamples, scales and lifts as it does over a stack.
struct Wave final : nonplanar::LayerField {
  static double k(double x) { return 0.2 * (1 + 0.2 * std::sin(x / 5)); }
  double T(double x, double, double z) const override { return z / k(x); }
  double z_at(double x, double, double t) const override { return t * k(x); }
  double zeta(double t) const override { return 0.2 * t; }
  double t_of_zeta(double z) const override { return z / 0.2; }
  double thickness(double x, double, double) const override { return k(x); }
  bool planar_at(double, double) const override { return false; }
};
// The shell's core cut back: kept on a wavy region up to z = 5, nothing above z = 10.
struct Waves final : nonplanar::LayerClip {
  Cover cover(double z) const override {
    return z < 2 ? Cover::all : z > 10 ? Cover::none : Cover::some;
  }
  double margin(double x, double y, double z) const override {
    return std::sin(x / 3) + std::cos(y / 4) - 0.2 * z;
  }
};
}  // namespace
#endif

#if NONPLANAR_FUZZ_PARSER == 10
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>

#include "nonplanar/gcode.hpp"
#include "nonplanar/slice.hpp"
#include "nonplanar/toolpaths.hpp"
namespace {
// A 10 × 10 × 1 mm box centred at `mid`.
nonplanar::TriangleMesh settings_box(const nonplanar::Vec2& mid) {
  nonplanar::TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back(mid.x() + (k & 1 ? 5 : -5), mid.y() + (k & 2 ? 5 : -5), k & 4 ? 1 : 0);
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// The code (before any comment, trailing blanks off) of a line.
std::string code_of(const std::string& line) {
  std::string code = line.substr(0, line.find(';'));
  while (!code.empty() && (code.back() == ' ' || code.back() == '\t' || code.back() == '\r'))
    code.pop_back();
  return code;
}

// Traps on a line the printer should never get: over 255 characters, a feed rate outside
// (0, 60000] mm/min (but in the profile's own blocks), a fan value outside 0…255, a non-finite
// number; or a move of the print (from its first extrusion to its last) off the bed.
void check_settings_output(const std::string& text, const nonplanar::PrintConfig& c) {
  // The profile's own G-code blocks pass as written, as PrusaSlicer passes them: a start G-code
  // "G1 Z5 F0000" (a mutated F5000) is the user's line, not one this program made.
  std::set<std::string> custom;
  for (const std::string* block :
       {&c.gcode.start_gcode, &c.gcode.end_gcode, &c.gcode.before_layer_gcode, &c.gcode.layer_gcode,
        &c.gcode.start_filament_gcode, &c.gcode.end_filament_gcode})
    for (std::size_t p = 0; p < block->size();) {
      const std::size_t e = std::min(block->find('\n', p), block->size());
      custom.insert(code_of(block->substr(p, e - p)));
      p = e + 1;
    }
  for (std::size_t p = 0; p < text.size();) {
    const std::size_t e = std::min(text.find('\n', p), text.size());
    const std::string line = text.substr(p, e - p);
    p = e + 1;
    if (line.size() > 255) __builtin_trap();
    const bool command = line.rfind("G0 ", 0) == 0 || line.rfind("G1 ", 0) == 0 ||
                         line.rfind("G92 ", 0) == 0 || line.rfind("M1", 0) == 0;
    // Numbers only: a comment may say anything ("; solid_infill_speed = 15" in an end G-code
    // once tripped this), and M117/M118 carry text.
    const std::string code = code_of(line);
    if (command && code.rfind("M117", 0) != 0 && code.rfind("M118", 0) != 0 &&
        (code.find("nan") != std::string::npos || code.find("inf") != std::string::npos))
      __builtin_trap();
    if ((line.rfind("G1 ", 0) == 0 || line.rfind("G0 ", 0) == 0) && !custom.count(code))
      if (const auto f = line.find(" F"); f != std::string::npos) {
        const double v = std::strtod(line.c_str() + f + 2, nullptr);
        if (!(v > 0 && v <= 60000)) __builtin_trap();
      }
    if (line.rfind("M106 S", 0) == 0) {
      const double v = std::strtod(line.c_str() + 6, nullptr);
      if (!(v >= 0 && v <= 255)) __builtin_trap();
    }
  }
  auto moves = nonplanar::read_gcode_moves(text);
  if (!moves) __builtin_trap();  // our own G-code must read back
  std::size_t first = moves->size(), last = 0;
  for (std::size_t i = 0; i < moves->size(); ++i)
    if ((*moves)[i].extruding && (*moves)[i].layer >= 0) first = std::min(first, i), last = i;
  for (std::size_t i = first; i <= last && i < moves->size(); ++i) {
    const nonplanar::Vec3& q = (*moves)[i].to;
    if (q.x() < c.bed_min.x() - 1e-3 || q.x() > c.bed_max.x() + 1e-3 ||
        q.y() < c.bed_min.y() - 1e-3 || q.y() > c.bed_max.y() + 1e-3)
      __builtin_trap();
  }
}
}  // namespace
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nonplanar;
  const std::string_view in(reinterpret_cast<const char*>(data), size);
#if NONPLANAR_FUZZ_PARSER == 0
  MeshFormat f;
  (void)io::parse_stl(in, &f);
#elif NONPLANAR_FUZZ_PARSER == 1
  (void)io::parse_obj(in);
#elif NONPLANAR_FUZZ_PARSER == 2
  (void)io::parse_off(in);
#elif NONPLANAR_FUZZ_PARSER == 3
  // With the objects asked for, as the loader asks: the slicers' object settings are read too.
  PlateObjects objects;
  if (auto m = io::parse_3mf(in, 50'000'000, &objects))
    if (objects.face.size() != m->faces.size() && objects.several()) __builtin_trap();
#elif NONPLANAR_FUZZ_PARSER == 4
  (void)parse_ini_config(in);
#elif NONPLANAR_FUZZ_PARSER == 5
  (void)parse_json_config(in);
#elif NONPLANAR_FUZZ_PARSER == 6
  (void)parse_surfaces_json(in);
#elif NONPLANAR_FUZZ_PARSER == 7
  // The thickness check measures on what it read (LayerGaps: grids over any coordinates).
  if (auto moves = read_gcode_moves(in)) {
    LayerGaps gaps;
    for (const PrintMove& m : *moves) gaps.add(m);
    gaps.finish();
  }
  (void)parse_ini_config(gcode_config_block(in));  // what `check` reads of a file's settings
  // Read a piece at a time (the mapping's reading), the same lines and moves.
  const GcodeProgram whole = read_gcode_program(in);
  GcodePieceReader pieces(in);
  std::size_t lines = 0, moves = 0;
  while (pieces.next(1))
    lines += pieces.program().lines.size(), moves += pieces.program().moves.size();
  if (lines != whole.lines.size() || moves != whole.moves.size()) __builtin_trap();
#elif NONPLANAR_FUZZ_PARSER == 8
  static const Wave field;
  // A layer at a time or 64 (the default), the same file.
  const auto mapped = map_foreign_gcode(in, field, {}, {});
  ForeignMapOptions one_layer;
  one_layer.layers_at_once = 1;
  const auto again = map_foreign_gcode(in, field, {}, {}, one_layer);
  if (mapped.ok() != again.ok() || (mapped && mapped->text() != again->text())) __builtin_trap();
  // Consumed as it is read (its read pages handed back: GcodePieceReader::held_from), the same
  // file: a view of a page gone would read zeros.
  const auto consumed = map_foreign_gcode_consuming(std::string(in), field, {}, {}, one_layer);
  if (consumed.ok() != again.ok() || (consumed && consumed->text() != again->text()))
    __builtin_trap();
  static const Waves clip;
  ForeignMapOptions o;
  o.clip = &clip;
  o.start = Vec3(100, 100, 3);
  o.start_retracted = 0.8;
  (void)map_foreign_gcode(in, field, {}, {}, o);
  // With a path inserted before every other layer (a shell's piece, near the nozzle): each
  // one a layer of the gate's, flagged as inserted.
  ForeignMapOptions ins = o;
  std::size_t given = 0;
  ins.before_layer = [&](double z, const Vec3& at) {
    std::vector<LayerToolpaths> out;
    if (given++ % 2) return out;
    LayerToolpaths L;
    ExtrusionPath p;
    p.width = 0.45, p.speed = 30;
    const double top = std::isfinite(z) ? z : at.z();
    p.points = {Vec3(at.x() + 1, at.y(), top + 0.05), Vec3(at.x() + 3, at.y() + 1, top + 0.1)};
    p.height = {0.2, 0.25};
    L.paths = {p};
    L.z = L.max_z = top + 0.1;
    out.push_back(std::move(L));
    return out;
  };
  ins.filament_per_mm = [](double w, double h) { return w * h / 2.4; };
  const auto inserted = map_foreign_gcode(in, field, {}, {}, ins);
  if (inserted && !inserted->inserted.empty() &&
      inserted->inserted.size() != inserted->layers.size())
    __builtin_trap();
  // Some of its lines spliced as the shell route splits a plate (program/splice_lines.hpp),
  // a third of them another object's, then mapped as its core.
  const GcodeProgram prog = read_gcode_program(in);
  std::vector<char> keep(prog.lines.size());
  for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = static_cast<char>(i % 3);
  std::string spliced;
  std::vector<char> marks;
  program::LineSplicer splice(prog);
  splice.append(0, prog.lines.size(), keep, spliced, &marks);
  o.planar_lines.assign(marks.size(), 0);
  for (std::size_t i = 0; i < marks.size(); ++i) o.planar_lines[i] = marks[i] == 2;
  (void)map_foreign_gcode(spliced, field, {}, {}, o);
#elif NONPLANAR_FUZZ_PARSER == 9
  // A head file that parses must also answer the collision search's queries.
  const auto shape = parse_toolhead_shape(in);
  if (!shape) return 0;
  Toolhead t;
  t.shape = *shape;
  const HeadClearance head(t), low(t, 2.0);
  for (const Vec2& d : {Vec2(0, 0), Vec2(3, -4), Vec2(-25, 10)})
    (void)head.allowance(d), (void)low.allowance(d), (void)head.block_allowance(d);
  (void)head.allowance_lower_bound(Vec2(-10, -10), Vec2(10, 10));
  (void)t.describe();
#elif NONPLANAR_FUZZ_PARSER == 10
  // Settings: any profile that validates must print a small box with every move of the print
  // on the bed and every number in a line the printer can take (hostile input #21.10: F
  // -2147483648, M106 S2550, lines cut at 255 characters, a skirt 457 m off the bed).
  auto c = parse_ini_config(in);
  if (!c) return 0;
  const Vec2 mid = c->bed_center();
  const TriangleMesh box = settings_box(mid);
  if (c->bed_max.x() - c->bed_min.x() < 12 || c->bed_max.y() - c->bed_min.y() < 12) return 0;
  auto layers = slice_mesh(box, c->slice, {});
  if (!layers) return 0;
  auto paths = make_toolpaths(*layers, c->paths, {});
  if (!paths) return 0;
  auto text = make_gcode(*paths, *c, {}, {});
  if (!text) {
    if (text.error().status == Status::internal_error) __builtin_trap();
    return 0;
  }
  check_settings_output(*text, *c);
#elif NONPLANAR_FUZZ_PARSER == 11
  // A custom G-code block: expanded or an error, with the variables a real print has.
  static const MacroVariables vars = [] {
    PrintConfig c;
    (void)set_config_value(c, "temperature", "210,200");
    (void)set_config_value(c, "printer_notes", "PRINTER_VENDOR_PRUSA3D\\nPRINTER_MODEL_MK3\\n");
    MacroVariables v = profile_variables(c);
    v.set("max_layer_z", MacroValue::real(23.45));
    return v;
  }();
  (void)expand_macros(in, vars, "start_gcode");
#elif NONPLANAR_FUZZ_PARSER == 12
  // A plan from a 3MF (post-process reads it from any file): refused, or a field that answers
  // everywhere over and around its part.
  auto plan = parse_plan_json(in);
  if (!plan) return 0;
  const BoundingBox& b = plan->box;
  if (!plan->shell.empty())  // a shell's plan: its fields answer over the box
    if (auto shell = layers::parse_shell_plan_json(plan->shell, {1.5, -2.5})) {
      const layers::ShellPathField f(*shell, shell->core.back() + shell->t);
      for (int i = 0; i <= 4; ++i) {
        const double x = b.min.x() - 5 + (b.size().x() + 10) * i / 4, y = b.max.y() - i;
        const double t = f.T(x, y, 0.5 * (b.min.z() + b.max.z()));
        if (std::isfinite(t)) (void)f.z_at(x, y, t), (void)f.z_at(x, y, 0.25);
        (void)f.t_of_zeta(b.max.z()), (void)shell->thickness(0, x, y);
      }
    }
  auto field = parse_layer_field_json(plan->field, {1.5, -2.5});
  if (!field) return 0;
  for (int i = 0; i <= 4; ++i)
    for (int k = 0; k <= 4; ++k) {
      const double x = b.min.x() - 5 + (b.size().x() + 10) * i / 4,
                   y = b.min.y() - 5 + (b.size().y() + 10) * k / 4;
      const double t = (*field)->T(x, y, 0.5 * (b.min.z() + b.max.z()));
      if (std::isfinite(t)) (void)(*field)->z_at(x, y, t);
      (void)(*field)->thickness(x, y, b.max.z());
      (void)(*field)->planar_along({x, y}, {y, x}, 0, 5);
    }
#else
#error "NONPLANAR_FUZZ_PARSER must name a parser (0-12)"
#endif
  return 0;
}
