// Moves straight from toolpaths, as the one reader (program/read_program.cpp) would read
// them from the written file: the safety gate's input.
#include <cmath>
#include <string>

#include "nonplanar/gcode.hpp"

namespace nonplanar {

std::vector<PrintMove> moves_from_toolpaths(
    const std::vector<LayerToolpaths>& layers, const GcodeParams& g,
    const std::function<bool(const ExtrusionPath&, int)>& keep) {
  std::vector<PrintMove> out;
  std::size_t n = 0;
  for (const LayerToolpaths& L : layers)
    for (const ExtrusionPath& p : L.paths) n += p.points.size();
  out.reserve(n);
  Vec3 pos(0, 0, 0);
  for (std::size_t li = 0; li < layers.size(); ++li)
    for (const ExtrusionPath& p : layers[li].paths) {
      if (p.points.empty() || (keep && !keep(p, static_cast<int>(li)))) continue;
      PrintMove t;
      t.from = pos, t.to = p.points[0], t.layer = static_cast<int>(li), t.type = role_name(p.role);
      t.width = p.width;
      out.push_back(t);
      for (std::size_t k = 1; k < p.points.size(); ++k) {
        PrintMove m;
        m.from = p.points[k - 1], m.to = p.points[k];
        m.filament = (m.to - m.from).norm() *
                     filament_per_mm(p.width, 0.5 * (p.height[k] + p.height[k - 1]), g);
        m.extruding = m.filament > 0 && (m.to.head<2>() - m.from.head<2>()).norm() > 1e-9;
        m.type = role_name(p.role), m.layer = static_cast<int>(li), m.width = p.width;
        out.push_back(m);
      }
      pos = p.points.back();
    }
  return out;
}

}  // namespace nonplanar
