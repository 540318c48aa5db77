// shell_split (shell_split.hpp): a shell plan's G-code cut into its core and its shell.
#include "engine/shell_split.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "program/splice_lines.hpp"

namespace nonplanar {

namespace {

Error refuse_split(const std::string& why) {
  return Error{Status::invalid_argument, why};
}

constexpr double kSplitSameZ = 2e-3;  ///< mm: the file writes ;Z: to 3 decimals

// Per layer of the file: whether the planned part extrudes in it, and whether another object
// does.
struct LayerUse {
  std::vector<char> ours, others;
};
LayerUse layer_use(const GcodeProgram& prog, const std::vector<char>& owner) {
  LayerUse u;
  u.ours.assign(prog.layer_z.size(), 0), u.others.assign(prog.layer_z.size(), 0);
  for (const GcodeMove& m : prog.moves)
    if (m.extruding() && m.layer >= 0 && static_cast<std::size_t>(m.layer) < u.ours.size())
      (owner[static_cast<std::size_t>(m.line - 1)] == kOthers
           ? u.others
           : u.ours)[static_cast<std::size_t>(m.layer)] = 1;
  return u;
}

// The part's layers above z_s: the first ends at z_s + t (its index, the plate), the rest on
// the t grid (the last may end short: the slicer's top is the mesh's).
Expected<std::size_t> plate_layer(const GcodeProgram& prog, const LayerUse& use, double z_s,
                                  double t) {
  const auto& z = prog.layer_z;
  std::vector<std::size_t> above;
  for (std::size_t k = 0; k < z.size(); ++k)
    if (use.ours[k] && z[k] > z_s + kSplitSameZ) above.push_back(k);
  char buf[320];
  if (above.size() < 2 || std::abs(z[above[0]] - (z_s + t)) > kSplitSameZ) {
    std::snprintf(buf, sizeof buf,
                  "no layer ends at z = %.3f mm, where the plan's shell begins: keep the object's "
                  "layer-height profile as prepared (variable layer height untouched)",
                  z_s + t);
    return refuse_split(buf);
  }
  for (std::size_t q = 1; q + 1 < above.size(); ++q) {
    const double j = (z[above[q]] - z_s) / t;
    if (std::abs(j - std::round(j)) > 0.01) {
      std::snprintf(buf, sizeof buf,
                    "layer %zu ends at z = %.3f mm, not on the plan's shell layers (%.3f mm "
                    "thick from %.3f): keep the object's layer-height profile as prepared",
                    above[q] + 1, z[above[q]], t, z_s);
      return refuse_split(buf);
    }
  }
  return above[0];
}

// The lines of the supports in the part's layers above `from` (mm): their moves, and the
// travels and retractions that lead to them (the slicer writes a support's ;TYPE: after the
// travel to it, and the splice must not go there). Their length in *mm; whether the part
// extrudes anything else there in *printed.
std::vector<char> support_lines(const GcodeProgram& prog, const std::vector<char>& owner,
                                double from, double* mm, bool* printed) {
  std::vector<char> support(prog.lines.size(), 0);
  std::vector<std::size_t> leading;  // moves since the last extrusion
  for (const GcodeMove& m : prog.moves) {
    if (m.layer < 0 || prog.layer_z[static_cast<std::size_t>(m.layer)] <= from || m.line <= 0 ||
        owner[static_cast<std::size_t>(m.line - 1)] == kOthers)
      continue;
    const auto line = static_cast<std::size_t>(m.line - 1);
    const bool of_support = role_from_name(m.type) == ExtrusionRole::support;
    if (!m.extruding()) {
      if (!m.has_xy && !m.has_e) continue;  // a layer change's Z
      if (of_support)
        support[line] = 1;
      else
        leading.push_back(line);
      continue;
    }
    if (of_support) {
      *mm += (m.to - m.from).norm();
      support[line] = 1;
      for (const std::size_t l : leading) support[l] = 1;
    } else {
      *printed = true;
    }
    leading.clear();
  }
  return support;
}

}  // namespace

Expected<ShellSplit> shell_split(const GcodeProgram& prog, std::string_view gcode,
                                 std::vector<char> owner, layers::ShellPlan plan) {
  if (owner.empty()) owner.assign(prog.lines.size(), kOurs);
  ShellSplit out;
  out.plan = std::move(plan);
  const double z_s = out.plan.core.back(), t = out.plan.t;
  const LayerUse use = layer_use(prog, owner);
  auto plate = plate_layer(prog, use, z_s, t);
  if (!plate) return plate.error();
  const double slab_from = prog.layer_z[*plate] + kSplitSameZ;
  // Supports the slicer put under the slab (it stands above the part in the 3MF) would be laid
  // on the part with the shell, where the shell lies on the core: left out, and their moves
  // with them (the splice travels and retracts as the next kept line needs). Those it put
  // under the slab in the core's layers stand where the shell goes, and the core's cut takes
  // them (map_shell_core).
  bool printed = false;
  const std::vector<char> support =
      support_lines(prog, owner, slab_from, &out.supports_left_out, &printed);
  if (!printed) return refuse_split("the shell's layers hold no extrusion of the part");

  // Which lines each program keeps: the core everything up to z_s, and above it the other
  // objects' lines and the layer changes among them; the shell the part's layers above the
  // plate. Both keep the start G-code; the end G-code follows as written.
  const std::size_t n = prog.lines.size();
  std::vector<char> core(n, 1), slab(n, 0);
  for (std::size_t i = 0; i < prog.print_begin && i < n; ++i) slab[i] = 1;
  for (std::size_t i = prog.print_begin; i < prog.print_end; ++i) {
    const char who = owner[i];
    if (who == kOthers) core[i] = 2;
    const int layer = prog.lines[i].layer;
    if (layer < 0) continue;
    const auto L = static_cast<std::size_t>(layer);
    const double z = prog.layer_z[L];
    if (z <= z_s + kSplitSameZ) continue;
    if (who != kOthers) core[i] = who == kUnlabelled && use.others[L];
    slab[i] = z > slab_from && use.ours[L] && who != kOthers && !support[i];
  }
  const std::string_view end = gcode.substr(
      prog.print_end < n
          ? static_cast<std::size_t>(prog.lines[prog.print_end].raw.data() - gcode.data())
          : gcode.size());
  program::LineSplicer core_lines(prog), shell_lines(prog);
  std::vector<char> marks;
  core_lines.append(0, prog.print_end, core, out.core, &marks);
  shell_lines.append(0, prog.print_end, slab, out.shell);
  if (!core_lines.problem().empty()) return refuse_split(core_lines.problem());
  if (!shell_lines.problem().empty()) return refuse_split(shell_lines.problem());
  out.core.append(end);
  out.shell.append(end);
  out.shares_plate = std::find(owner.begin(), owner.end(), kOthers) != owner.end();
  out.others.resize(marks.size());
  for (std::size_t i = 0; i < marks.size(); ++i) out.others[i] = marks[i] == 2;
  return out;
}

}  // namespace nonplanar
