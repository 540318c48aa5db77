// post_process_gcode (print_plan.hpp): the slicer's own route, after its post-processing hook.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>

#include "core/huge_pages.hpp"
#include "core/polygon_ops.hpp"
#include "engine/shell_engine.hpp"
#include "engine/shell_split.hpp"
#include "layers/shell_plan.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/field_io.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/program.hpp"
#include "pipeline/gate.hpp"

namespace nonplanar {

namespace {

Error refuse(const std::string& why) {
  return Error{Status::invalid_argument, why};
}

// "key = value" of the settings block (empty when the key is not there).
std::string block_value(const std::string& block, const std::string& key) {
  const std::string head = key + " = ";
  for (std::size_t at = 0; at < block.size();) {
    const std::size_t end = std::min(block.find('\n', at), block.size());
    if (block.compare(at, head.size(), head) == 0)
      return block.substr(at + head.size(), end - at - head.size());
    at = end + 1;
  }
  return "";
}

// A label's object name without the slicer's id and copy ("dome id:0 copy 0", "dome_id_0_copy_0",
// "dome.stl") and quotes.
std::string object_name(std::string n) {
  for (const char* cut : {" id:", "_id_"})
    if (auto at = n.find(cut); at != std::string::npos) n.resize(at);
  while (!n.empty() && (n.back() == '"' || n.back() == '\'' || n.back() == ' ')) n.pop_back();
  while (!n.empty() && (n.front() == '"' || n.front() == '\'')) n.erase(0, 1);
  for (const char* ext : {".stl", ".STL", ".3mf", ".3MF", ".obj", ".OBJ", ".step", ".stp"})
    if (n.size() > std::strlen(ext) &&
        n.compare(n.size() - std::strlen(ext), std::string::npos, ext) == 0)
      n.resize(n.size() - std::strlen(ext));
  return n;
}

// Object labels as the slicers write them: PrusaSlicer 2.5's "; printing object NAME id:0
// copy 0" / "; stop printing object", 2.6+'s firmware labels M486 S<id> A"NAME" / M486 S-1
// (a later M486 S<id> starts that object again), Klipper's EXCLUDE_OBJECT_START NAME=… /
// EXCLUDE_OBJECT_END, and for Bambu Lab printers (OrcaSlicer, Bambu Studio) "; start printing
// object, unique label id: N" / "; stop printing object, unique label id: N", which name no
// object: their start reads as kIdOnly + N, and only in a file with no named label (OrcaSlicer
// writes both when asked for both).
enum class Label { none, start, end };
constexpr std::string_view kIdOnly = "label id ";
class LabelReader {
 public:
  /// What line `raw` says; for a start, *name is the object's (object_name).
  Label read(std::string_view raw, std::string* name) {
    static const std::pair<std::string_view, Label> kHeads[] = {
        {"; printing object ", Label::start},
        {"; stop printing object", Label::end},
        {"EXCLUDE_OBJECT_START NAME=", Label::start},
        {"EXCLUDE_OBJECT_END", Label::end}};
    constexpr std::string_view kIdStart = "; start printing object, unique label id: ";
    if (raw.substr(0, kIdStart.size()) == kIdStart) {
      if (named_) return Label::none;
      *name = std::string(kIdOnly) + object_name(std::string(raw.substr(kIdStart.size(), 20)));
      return Label::start;
    }
    for (const auto& [head, kind] : kHeads)
      if (raw.substr(0, head.size()) == head) {
        if (kind == Label::start)
          *name = object_name(std::string(raw.substr(head.size(), 200))), named_ = true;
        return kind;
      }
    if (raw.substr(0, 6) != "M486 S") return Label::none;
    const long id = std::strtol(std::string(raw.substr(6, 12)).c_str(), nullptr, 10);
    if (id < 0) return Label::end;
    if (const auto a = raw.find(" A"); a != std::string_view::npos)
      names_[id] = object_name(std::string(raw.substr(a + 2, 200)));
    const auto it = names_.find(id);
    if (it == names_.end()) return Label::none;
    *name = it->second, named_ = true;
    return Label::start;
  }

 private:
  std::map<long, std::string> names_;
  bool named_ = false;  ///< a label with a name was read
};

// The part's outline in the slicer's words (PrusaSlicer's, OrcaSlicer's): supports and the
// brim reach beyond it (PrusaSlicer 2.5's support base grows 5 mm past the part).
bool outline(std::string_view type) {
  return type == "External perimeter" || type == "Overhang perimeter" || type == "Outer wall" ||
         type == "Overhang wall";
}
bool not_the_part(std::string_view type) {
  const ExtrusionRole r = role_from_name(type);
  return r == ExtrusionRole::skirt || r == ExtrusionRole::support;
}

// The settings the plan needs kept, checked against the file: the layers as sliced (a
// per-object layer height does not show in the block, so the ;HEIGHT: of each layer is
// read), arc fitting, spiral vase.
std::optional<Error> settings_kept(const GcodeProgram& prog, const std::vector<char>& ours,
                                   const std::string& block, const PrintPlan& plan) {
  char buf[300];
  const auto& h = prog.layer_height;
  if (h.empty())
    return refuse("no ;LAYER_CHANGE in the file: is it PrusaSlicer's or OrcaSlicer's?");
  if (std::abs(h[0] - plan.first_layer_height) > 1e-3) {
    std::snprintf(buf, sizeof buf,
                  "the first layer is %.3f mm, the plan's %.3f mm: set first_layer_height = %.3f "
                  "(Print Settings > Layers and perimeters), or prepare again with yours",
                  h[0], plan.first_layer_height, plan.first_layer_height);
    return refuse(buf);
  }
  // The part's beads (not the supports', which PrusaSlicer puts on layers of their own between
  // the part's); its last layer may be thinner (the top is not on a layer boundary everywhere).
  auto of_part = [&](std::size_t i) {
    return ours[i] && prog.moves[i].extruding() && !not_the_part(prog.moves[i].type);
  };
  int first = -1, last = 0;
  for (std::size_t i = 0; i < prog.moves.size(); ++i)
    if (of_part(i)) {
      if (first < 0) first = prog.moves[i].layer;
      last = std::max(last, prog.moves[i].layer);
    }
  // A shell's layers are its plan's core boundaries, then its own (shell_split checks them).
  for (std::size_t i = 0; i < prog.moves.size() && plan.shell.empty(); ++i) {
    const GcodeMove& m = prog.moves[i];
    if (of_part(i) && m.layer > first && m.layer < last &&
        std::abs(m.height - plan.layer_height) > 1e-3) {
      std::snprintf(buf, sizeof buf,
                    "layer %d is %.3f mm (line %d), the plan's layers %.3f mm: keep layer_height = "
                    "%.3f on the object and variable layer height off, or prepare again with yours",
                    m.layer + 1, m.height, m.line, plan.layer_height, plan.layer_height);
      return refuse(buf);
    }
  }
  const std::string arcs = block_value(block, "arc_fitting");
  if (!arcs.empty() && arcs != "disabled" && arcs != "0")
    return refuse("arc_fitting = " + arcs +
                  ": arcs cannot follow curved layers; set "
                  "arc_fitting = disabled (Print Settings > Advanced)");
  if (block_value(block, "spiral_vase") == "1")
    return refuse("spiral_vase = 1: a spiral vase has no layers to map; switch it off");
  return std::nullopt;
}

// A closed loop's area centroid (shoelace), and its signed area in *a.
Vec2 centroid(const std::vector<Vec2>& loop, double* a) {
  double twice = 0;
  Vec2 c(0, 0);
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Vec2& p = loop[i];
    const Vec2& q = loop[(i + 1) % loop.size()];
    const double cross = p.x() * q.y() - q.x() * p.y();
    twice += cross, c += (p + q) * cross;
  }
  *a = 0.5 * twice;
  return twice != 0 ? Vec2(c / (3 * twice)) : c;
}

// Where the slicer put the part, to a hundredth of a millimetre where the box is off by a
// tenth (a wing's trailing edge: its outer perimeter stops short of the thin end, and the
// box's centre moved 0.08 mm): the centroid of the largest loop of outer perimeter in the
// plan's anchor layer against the anchor's, inset by half that perimeter's width as the
// slicer insets it. None when the layer or a loop is missing.
std::optional<Vec2> anchored(const GcodeProgram& prog, const std::vector<char>& ours,
                             const PrintPlan& plan) {
  if (plan.anchor.size() < 3) return std::nullopt;
  int layer = -1;
  for (std::size_t k = 0; k < prog.layer_z.size() && layer < 0; ++k)
    if (std::abs(prog.layer_z[k] - plan.anchor_z) < 2e-3) layer = static_cast<int>(k);
  std::vector<Vec2> loop, best;
  double best_area = 0, width = 0, best_width = 0;
  const auto close = [&] {
    double a = 0;
    if (loop.size() >= 3) centroid(loop, &a);
    if (std::abs(a) > best_area) best_area = std::abs(a), best = loop, best_width = width;
    loop.clear();
  };
  for (std::size_t i = 0; i < prog.moves.size() && layer >= 0; ++i) {
    const GcodeMove& m = prog.moves[i];
    if (m.layer != layer) {
      if (m.layer > layer) break;
      continue;
    }
    const Vec2 from = m.from.head<2>(), to = m.to.head<2>();
    if (ours[i] && m.extruding() && outline(m.type)) {
      if (!loop.empty() && (loop.back() - from).norm() > 1e-3) close();
      if (loop.empty()) loop.push_back(from);
      loop.push_back(to), width = m.width;
    } else if (!m.extruding() && (to - from).norm() > 1e-3) {
      close();
    }
  }
  close();
  if (best_area <= 0) return std::nullopt;
  double most = 0;
  Vec2 want(0, 0);
  for (const ExPolygon& e : clip::offset_ex({ExPolygon{plan.anchor, {}}}, -0.5 * best_width)) {
    double a = 0;
    const Vec2 c = centroid(e.contour, &a);
    if (std::abs(a) > most) most = std::abs(a), want = c;
  }
  double unused = 0;
  if (most <= 0) return std::nullopt;
  return Vec2(centroid(best, &unused) - want);
}

// Whether an outline's box (XY, mm) is the plan's size: perimeters lie half a width inside the
// part, and a part is never wider than itself.
bool planned_size(const Vec2& got, const Vec2& want) {
  return (got.array() <= want.array() + 0.2).all() && (got.array() >= want.array() - 2.0).all();
}

// Where the slicer put the part: the box of its outline (its outer perimeters; without any,
// every extrusion of the part) against the plan's. A part keeps its size when only moved;
// scaled, rotated, or with other objects on the plate, the box's size differs.
Expected<Vec2> placement(const GcodeProgram& prog, const std::vector<char>& ours,
                         const PrintPlan& plan) {
  BoundingBox b;
  for (const bool outer_only : {true, false}) {
    for (std::size_t i = 0; i < prog.moves.size(); ++i) {
      const GcodeMove& m = prog.moves[i];
      if (ours[i] && m.layer >= 0 && m.extruding() &&
          (outer_only ? outline(m.type) : !not_the_part(m.type)))
        b.extend(m.from), b.extend(m.to);
    }
    if (!b.empty()) break;
  }
  if (b.empty()) return refuse("the file extrudes nothing but skirt, brim and supports");
  const Vec2 got = b.size().head<2>(), want = plan.box.size().head<2>();
  if (!planned_size(got, want)) {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "the part in the G-code is %.1f x %.1f mm, the plan's %.1f x %.1f mm: it was "
                  "scaled or rotated after prepare (move it, but do not scale or rotate it), "
                  "or the plate holds other objects (switch on Label objects, Print Settings > "
                  "Output options, so post-process can tell them apart)",
                  got.x(), got.y(), want.x(), want.y());
    return refuse(buf);
  }
  if (auto at = anchored(prog, ours, plan)) return *at;
  return Vec2(0.5 * (b.min + b.max).head<2>() - 0.5 * (plan.box.min + plan.box.max).head<2>());
}

// Of labels that name no object (Bambu's ids): the one whose outline is the plan's size, as
// placement measures it (empty: none or several).
std::string sized_as_planned(const GcodeProgram& prog, const std::vector<int>& label_of_line,
                             const std::vector<std::string>& names, const PrintPlan& plan) {
  std::vector<BoundingBox> box(names.size());
  for (const GcodeMove& m : prog.moves) {
    const int k = m.line > 0 ? label_of_line[static_cast<std::size_t>(m.line - 1)] : -1;
    if (k >= 0 && m.layer >= 0 && m.extruding() && outline(m.type))
      box[static_cast<std::size_t>(k)].extend(m.from),
          box[static_cast<std::size_t>(k)].extend(m.to);
  }
  const Vec2 want = plan.box.size().head<2>();
  std::string found;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (box[k].empty()) continue;
    if (planned_size(box[k].size().head<2>(), want)) {
      if (!found.empty()) return {};
      found = names[k];
    }
  }
  return found;
}

// Whose each line is (LineOwner): with object labels naming several objects, a line between
// another object's start and end labels is that object's (the labels too); else every line is
// the part's or outside labels. Labels that name no object (Bambu's ids): the part is the one
// object of the plan's size. Refused when the labels name several objects and none is the
// plan's.
Expected<std::vector<char>> line_owners(const GcodeProgram& prog, const PrintPlan& plan) {
  std::vector<int> label_of_line(prog.lines.size(), -1);
  std::vector<std::string> names;
  std::string name;
  int current = -1;
  LabelReader labels;
  for (std::size_t i = 0; i < prog.lines.size(); ++i) {
    const GcodeLine& l = prog.lines[i];
    const Label k = l.kind == GcodeLine::Kind::text ? labels.read(l.raw, &name) : Label::none;
    if (k == Label::start) {
      const auto it = std::find(names.begin(), names.end(), name);
      current = static_cast<int>(it - names.begin());
      if (it == names.end()) names.push_back(name);
    }
    label_of_line[i] = current;
    if (k == Label::end) current = -1;
  }
  std::vector<char> owner(prog.lines.size(), kUnlabelled);
  // One object on the plate is the planned one, whatever the user renamed it to.
  if (names.size() <= 1) {
    for (std::size_t i = 0; i < owner.size(); ++i)
      if (label_of_line[i] >= 0) owner[i] = kOurs;
    return owner;
  }
  std::string part = plan.object;
  if (std::all_of(names.begin(), names.end(),
                  [](const std::string& n) { return n.rfind(kIdOnly, 0) == 0; })) {
    part = sized_as_planned(prog, label_of_line, names, plan);
    if (part.empty()) {
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "the plate's %zu objects are labelled by number only (Bambu Lab's labels), "
                    "and not one alone has the plan's size (%.1f x %.1f mm): print it alone, "
                    "or beside objects of another size",
                    names.size(), plan.box.size().x(), plan.box.size().y());
      return refuse(buf);
    }
  }
  if (std::find(names.begin(), names.end(), part) == names.end()) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    return refuse("the plate's objects are " + list + "; none is " + plan.object +
                  ", the plan's (keep the name prepare gave it)");
  }
  for (std::size_t i = 0; i < owner.size(); ++i)
    if (label_of_line[i] >= 0)
      owner[i] = names[static_cast<std::size_t>(label_of_line[i])] == part ? kOurs : kOthers;
  return owner;
}

// Per move: whether it is the planned part's or the field's (moves outside every label:
// travels between objects, layer changes), not another object's.
std::vector<char> moves_of_part(const GcodeProgram& prog, const std::vector<char>& owner) {
  std::vector<char> ours(prog.moves.size(), 1);
  for (std::size_t i = 0; i < prog.moves.size(); ++i)
    if (prog.moves[i].line > 0)
      ours[i] = owner[static_cast<std::size_t>(prog.moves[i].line - 1)] != kOthers;
  return ours;
}

// What the file must keep of the plan (settings_kept), where the part went (placement), and
// which moves are other objects' (kept planar). Its own reading of the file is gone when it
// returns: map_foreign_gcode reads the file again, and the bunny's 14.7 MB file read twice
// at once held about 100 MB more.
struct Checked {
  Vec2 moved{0, 0};
  ForeignMapOptions options;
  std::optional<ShellSplit> split;  ///< a shell plan's
};
Expected<Checked> checked_placement(std::string_view gcode, const std::string& block,
                                    const PrintPlan& plan) {
  const GcodeProgram prog = read_gcode_program(gcode);
  for (const GcodeProblem& q : prog.problems)
    if (q.why.rfind("arc move", 0) == 0)
      return refuse("line " + std::to_string(q.line) +
                    " is an arc (G2/G3): switch arc fitting off (Print Settings > Advanced > "
                    "Arc fitting; OrcaSlicer: Process > Quality), arcs cannot follow curved "
                    "layers");
  auto owner = line_owners(prog, plan);
  if (!owner) return owner.error();
  const std::vector<char> ours = moves_of_part(prog, *owner);
  auto moved = placement(prog, ours, plan);
  if (!moved) return moved.error();
  if (auto e = settings_kept(prog, ours, block, plan)) return *e;
  Checked c;
  c.moved = *moved;
  if (!plan.shell.empty()) {
    auto shell = layers::parse_shell_plan_json(plan.shell);
    if (!shell) return shell.error();
    auto split = shell_split(prog, gcode, std::move(*owner), std::move(*shell));
    if (!split) return split.error();
    c.split = std::move(*split);
    return c;
  }
  if (std::find(ours.begin(), ours.end(), 0) != ours.end()) {
    c.options.planar_lines.assign(prog.lines.size(), 0);
    for (std::size_t i = 0; i < prog.lines.size(); ++i)
      c.options.planar_lines[i] = (*owner)[i] == kOthers;
  }
  return c;
}

// A shell plan's G-code mapped as the engine route maps its run: the core (the file
// without the shell's layers and the layer under them; other objects as written) cut back
// under the shell; the shell's layers mapped onto the shell; joined.
Expected<EngineShell> map_shell_gcode(ShellSplit& sp, const Vec2& moved, const SliceJob& job,
                                      const Context& ctx) {
  const layers::ShellPlan& shell = sp.plan;
  sp.plan.top.origin += moved;  // H follows the part on the plate
  const EngineRoute route{job.engine, job.print, job.layers, job.map_back};
  auto core = map_shell_core(std::move(sp.core), shell, route, ctx, std::move(sp.others));
  if (!core) return core.error();
  return join_shell(std::move(*core), sp.shell, shell, shell.core.back() + shell.t, route,
                    "the shell's curved layers, from the slicer's layers above the core", ctx);
}

// Whether a mark of ours heads our header, which the time estimate's first M73 lines may
// precede (a profile with remaining_times, as the MK3S's): looked for before the first layer.
bool marked(std::string_view gcode, std::string_view mark) {
  const std::string_view head = gcode.substr(0, gcode.find("\n;LAYER_CHANGE"));
  return head.substr(0, mark.size()) == mark ||
         head.find("\n" + std::string(mark)) != std::string_view::npos;
}
bool post_processed(std::string_view gcode) {
  return marked(gcode, kPostProcessedMark);
}

}  // namespace

std::optional<Vec2> post_processed_centre(std::string_view gcode) {
  if (!post_processed(gcode) && !marked(gcode, kGeneratedMark)) return std::nullopt;
  const std::string_view head = gcode.substr(0, gcode.find("\n;LAYER_CHANGE"));
  const std::size_t at = head.find(kPartCentredAt);
  double x = 0, y = 0;
  if (at == std::string_view::npos ||
      std::sscanf(std::string(head.substr(at + kPartCentredAt.size(), 80)).c_str(), "%lf, %lf", &x,
                  &y) != 2 ||
      !std::isfinite(x) || !std::isfinite(y))
    return std::nullopt;
  return Vec2(x, y);
}

std::vector<std::string> gcode_object_names(std::string_view gcode) {
  std::vector<std::string> names;
  LabelReader labels;
  std::string name;
  for (std::size_t at = 0; at < gcode.size() && names.size() < 64;) {
    const std::size_t end = std::min(gcode.find('\n', at), gcode.size());
    const char c = gcode[at];
    if ((c == ';' || c == 'M' || c == 'E') &&
        labels.read(gcode.substr(at, end - at), &name) == Label::start &&
        name.rfind(kIdOnly, 0) != 0 && std::find(names.begin(), names.end(), name) == names.end())
      names.push_back(name);
    at = end + 1;
  }
  return names;
}

Expected<PostProcessed> post_process_gcode(std::string_view gcode, const PrintPlan& plan,
                                           const Context& ctx) {
  if (post_processed(gcode))
    return refuse("already post-processed by nonplanar (mapping it twice would lift it twice)");
  const std::string block = gcode_config_block(gcode);
  if (block.empty())
    return refuse(
        "no settings block at its end: post-process reads PrusaSlicer's and "
        "OrcaSlicer's G-code (is this file complete?)");
  auto cfg = parse_ini_config(block);
  if (!cfg) return refuse("its settings block: " + cfg.error().message);
  auto checked = checked_placement(gcode, block, plan);
  if (!checked) return checked.error();
  const Vec2 moved = checked->moved;
  // The plan's layers, limits and head; the file's printer for everything else.
  cfg->slice.layer_height = plan.layer_height;
  cfg->slice.first_layer_height = plan.first_layer_height;
  cfg->min_layer_height = plan.min_layer_height;
  cfg->max_layer_height = plan.max_layer_height;
  cfg->toolhead = plan.toolhead;
  SliceJob job = make_job(*cfg, plan.max_angle_deg);
  auto field = parse_layer_field_json(plan.field, moved);
  if (!field) return field.error();
  char buf[240];
  std::snprintf(buf, sizeof buf, "%s %s from %s (plan of %s; the part moved by %.3f, %.3f mm)\n",
                kPostProcessedMark.data(), "0.1.0", plan.object.c_str(), plan.model.c_str(),
                moved.x(), moved.y());
  std::string head = buf;
  const Vec2 centre = 0.5 * (plan.box.min + plan.box.max).head<2>() + moved;
  std::snprintf(buf, sizeof buf, "%s%.3f, %.3f mm on the plate\n", kPartCentredAt.data(),
                centre.x(), centre.y());
  head += buf;
  for (const std::string& h : plan.header) head += "; " + h + "\n";
  SliceResult r;
  if (checked->split) {
    auto joined = map_shell_gcode(*checked->split, moved, job, ctx);
    if (!joined) return joined.error();
    r.layers = std::move(joined->layers);
    r.gcode = joined_huge({head, joined->gcode});
  } else {
    auto mapped = map_foreign_gcode(gcode, **field, job.map_back, ctx, checked->options);
    if (!mapped) return mapped.error();
    r.layers = std::move(mapped->layers);
    r.gcode = mapped->take_text(head);
  }
  r.nonplanar = true;
  std::string breach;
  auto ok = gate(
      r, job, checked->split ? nullptr : dynamic_cast<const layers::BandedField*>(field->get()),
      [&](const Vec3& p, const char* what) {
        std::snprintf(buf, sizeof buf, "%s at (%.2f, %.2f, %.2f)", what, p.x(), p.y(), p.z());
        breach = buf;
        return false;
      },
      ctx);
  if (!ok) return ok.error();
  // A shell prints after everything else on the plate: an object near it standing higher
  // is in the head's way.
  if (!*ok && checked->split && checked->split->shares_plate) {
    std::snprintf(buf, sizeof buf, "%.0f", job.check.toolhead.reach());
    return Error{Status::internal_error,
                 "safety check: " + breach + "; the shell prints after the plate's other " +
                     "objects, and one standing within " + buf + " mm of " + plan.object +
                     " (the print head's reach) may be in its way: move them farther apart or " +
                     "print them separately; the file is left as the slicer wrote it"};
  }
  if (!*ok)
    return Error{Status::internal_error,
                 "safety check: " + breach +
                     "; the file is left as the slicer wrote it (prepare again with "
                     "--check-with prusaslicer and this profile: the patches its paths break "
                     "then stay planar)"};
  PostProcessed out;
  if (checked->split && checked->split->supports_left_out > 0) {
    std::snprintf(buf, sizeof buf,
                  "left out %.0f mm of supports the slicer put under the shell's layers (they "
                  "stood above the part in the 3MF; the shell lies on the core there)",
                  checked->split->supports_left_out);
    out.notices.push_back(buf);
  }
  // The gate measured them (job.print is *cfg).
  out.gcode = r.stats_in_gcode ? std::move(r.gcode) : with_print_stats(r.gcode, *cfg, &out.stats);
  if (r.stats_in_gcode) out.stats = r.stats;
  out.moved = moved;
  out.layers = r.layers.size();
  out.thickness_min = r.thickness_min, out.thickness_max = r.thickness_max;
  out.steepest_deg = r.steepest_deg;
  return out;
}

}  // namespace nonplanar
