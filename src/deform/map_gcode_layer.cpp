// map_gcode_layer (map_gcode_layer.hpp): a planar G-code layer onto the curved layers.
#include "deform/map_gcode_layer.hpp"

#include <algorithm>

#include "core/parallel.hpp"
#include "deform/map_segment.hpp"

namespace nonplanar {

bool kept_planar(const std::vector<char>& planar_lines, const GcodeMove& m) {
  const auto k = static_cast<std::size_t>(m.line - 1);
  return m.line > 0 && k < planar_lines.size() && planar_lines[k];
}

std::optional<Error> map_gcode_layer(std::span<const GcodeLine> lines,
                                     const std::vector<GcodeMove>& moves,
                                     program::MovePaths& mapped, const LayerField& field,
                                     const MapBackParams& params,
                                     const std::vector<char>& planar_lines, LayerToolpaths& L,
                                     std::size_t& points) {
  L.max_z = -1e300;
  for (const GcodeLine& it : lines) {
    if (it.kind != GcodeLine::Kind::move) continue;
    const GcodeMove& m = moves[static_cast<std::size_t>(it.move)];
    if (!m.has_xy || !(m.extruding() || (m.wipe && m.de <= 0))) continue;
    ExtrusionPath& p = mapped[static_cast<std::size_t>(it.move)];
    if (kept_planar(planar_lines, m)) {
      p.points = {m.from, m.to};
      p.height = {m.height, m.height};
      p.object = 1;  // another object's (ExtrusionPath::object)
      add_to_reach(p, L);
      continue;
    }
    const Mapped a = map_point(field, m.from, m.height), b = map_point(field, m.to, m.height);
    p.points.push_back(a.p);
    p.height.push_back(a.height);
    map_segment(field, m.from, a, m.to, b, m.height, params, 0, p);
    points += p.points.size();
    if (points > params.most_points)
      return Error{Status::invalid_argument, "line " + std::to_string(m.line) + ": more than " +
                                                 std::to_string(params.most_points) +
                                                 " mapped points"};
    add_to_reach(p, L);
  }
  if (L.max_z < -1e299) L.max_z = 0;
  return std::nullopt;
}

std::vector<GcodeLayerSpan> gcode_layer_spans(std::span<const GcodeLine> lines) {
  std::vector<GcodeLayerSpan> spans;
  for (std::size_t i = 0; i < lines.size();) {
    std::size_t j = i + 1;
    while (j < lines.size() && lines[j].raw.rfind(";LAYER_CHANGE", 0) != 0) ++j;
    spans.push_back({i, j, static_cast<std::size_t>(std::max(lines[i].layer, 0))});
    i = j;
  }
  return spans;
}

std::vector<std::size_t> map_gcode_layers(std::span<const GcodeLine> lines,
                                          const std::vector<GcodeLayerSpan>& spans,
                                          const std::vector<GcodeMove>& moves,
                                          program::MovePaths& mapped, const LayerField& field,
                                          const MapBackParams& params,
                                          const std::vector<char>& planar_lines,
                                          std::vector<LayerToolpaths>& layers, const Context& ctx) {
  std::vector<std::size_t> points(spans.size(), kFailed);
  // Each layer writes only its own moves' entries of `mapped` and its own LayerToolpaths.
  core::parallel_for(std::size_t(0), spans.size(), [&](std::size_t k) {
    if (ctx.cancelled()) return;
    const GcodeLayerSpan& s = spans[k];
    std::size_t n = 0;
    if (!map_gcode_layer(lines.subspan(s.begin, s.end - s.begin), moves, mapped, field, params,
                         planar_lines, layers[s.layer], n))
      points[k] = n;
  });
  return points;
}

}  // namespace nonplanar
