// make_toolpaths: perimeters, skins, infill and skirt per layer (DESIGN.md §2 step 6).
#include <atomic>
#include <cmath>

#include "core/parallel.hpp"
#include "toolpaths/toolpath_parts.hpp"

namespace nonplanar {

const char* role_name(ExtrusionRole r) {
  switch (r) {
    case ExtrusionRole::external_perimeter:
      return "External perimeter";
    case ExtrusionRole::perimeter:
      return "Perimeter";
    case ExtrusionRole::internal_infill:
      return "Internal infill";
    case ExtrusionRole::solid_infill:
      return "Solid infill";
    case ExtrusionRole::top_solid_infill:
      return "Top solid infill";
    case ExtrusionRole::skirt:
      return "Skirt/Brim";
    case ExtrusionRole::support:
      return "Support material";
  }
  return "Custom";
}

ExtrusionRole role_from_name(std::string_view type) {
  if (type == "External perimeter" || type == "Overhang perimeter")
    return ExtrusionRole::external_perimeter;
  if (type == "Perimeter") return ExtrusionRole::perimeter;
  if (type == "Internal infill") return ExtrusionRole::internal_infill;
  if (type == "Top solid infill" || type == "Ironing") return ExtrusionRole::top_solid_infill;
  if (type == "Skirt/Brim" || type == "Skirt" || type == "Brim") return ExtrusionRole::skirt;
  if (type.find("Support") != std::string_view::npos ||
      type.find("support") != std::string_view::npos)
    return ExtrusionRole::support;
  return ExtrusionRole::solid_infill;
}

double bead_spacing(double width, double height) {
  return width - height * (1.0 - M_PI / 4.0);
}

double filament_per_mm(double width, double height, const GcodeParams& g) {
  const double area = height * bead_spacing(width, height);  // rectangle with round ends
  const double filament = M_PI * 0.25 * g.filament_diameter * g.filament_diameter;
  return area / filament * g.extrusion_multiplier;
}

namespace {

using paths::ExPolygons;

struct LayerRegions {
  std::vector<std::vector<std::vector<Polygon>>> loops;  // per island: perimeter rings
  ExPolygons fill;                                       // area left for infill
};

ExtrusionPath make_path(ExtrusionRole role, double width, double speed, const Polygon& pts,
                        bool closed, double z, double h) {
  ExtrusionPath p;
  p.role = role;
  p.width = width;
  p.speed = speed;
  for (const Vec2& v : pts) p.points.emplace_back(v.x(), v.y(), z);
  if (closed && !pts.empty()) p.points.emplace_back(pts.front().x(), pts.front().y(), z);
  p.height.assign(p.points.size(), h);
  return p;
}

}  // namespace

Expected<std::vector<LayerToolpaths>> make_toolpaths(const std::vector<SlicedLayer>& layers,
                                                     const ToolpathParams& P, const Context& ctx) {
  ctx.progress("toolpaths", 0);
  if (!(P.extrusion_width > 0) || !(P.perimeter_width > 0) || !(P.external_perimeter_width > 0) ||
      !(P.first_layer_width > 0))
    return Error{Status::invalid_argument, "extrusion_width: must be > 0"};
  if (!(P.fill_density >= 0 && P.fill_density <= 1))
    return Error{Status::invalid_argument, "fill_density: must be in [0, 1]"};
  const std::size_t n = layers.size();
  std::vector<LayerRegions> reg(n);
  std::atomic<bool> stop{false};
  // Pass 1: perimeters and the infill area of every island.
  core::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    if (stop || ctx.cancelled()) return stop = true, void();
    const double h = layers[i].z_top - layers[i].z_bottom;
    const double wp = i == 0 ? P.first_layer_width : P.perimeter_width;
    const double we = i == 0 ? P.first_layer_width : P.external_perimeter_width;
    for (const ExPolygon& island : layers[i].islands) {
      ExPolygons inner;
      reg[i].loops.push_back(
          paths::perimeter_loops({island}, P.perimeters, we, bead_spacing(wp, h), &inner));
      reg[i].fill.insert(reg[i].fill.end(), inner.begin(), inner.end());
    }
  });
  if (stop) return Error{Status::cancelled, "cancelled"};
  ctx.progress("toolpaths", 0.4);

  auto covers = [&](std::size_t k) -> const ExPolygons& {
    return layers[k].covers.empty() ? layers[k].islands : layers[k].covers;
  };
  std::vector<LayerToolpaths> out(n);
  core::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    if (stop || ctx.cancelled()) return stop = true, void();
    const SlicedLayer& L = layers[i];
    const double h = L.z_top - L.z_bottom, z = L.z_top;
    const double w = i == 0 ? P.first_layer_width : P.extrusion_width;
    const double wp = i == 0 ? P.first_layer_width : P.perimeter_width;
    const double we = i == 0 ? P.first_layer_width : P.external_perimeter_width;
    const double s = bead_spacing(w, h);
    auto speed = [&](double v) { return i == 0 ? std::min(v, P.first_layer_speed) : v; };
    LayerToolpaths& T = out[i];
    T.z = z;
    T.height = h;
    T.max_z = z;
    // Skins: solid where there is air within top_solid_layers above or bottom_solid_layers
    // below; "top" where the very next layer does not cover it.
    const ExPolygons& fill = reg[i].fill;
    ExPolygons covered_above, covered_below;
    bool all_top = false, all_bottom = false;
    for (int j = 1; j <= P.top_solid_layers; ++j) {
      if (i + j >= n) {
        all_top = true;
        break;
      }
      covered_above = j == 1 ? covers(i + j) : clip::intersection_ex(covered_above, covers(i + j));
    }
    for (int j = 1; j <= P.bottom_solid_layers; ++j) {
      if (static_cast<int>(i) - j < 0) {
        all_bottom = true;
        break;
      }
      covered_below = j == 1 ? layers[i - j].islands
                             : clip::intersection_ex(covered_below, layers[i - j].islands);
    }
    const ExPolygons top = all_top && P.top_solid_layers > 0
                               ? fill
                               : clip::diff_ex(fill, P.top_solid_layers > 0 ? covered_above : fill);
    const ExPolygons bottom =
        all_bottom && P.bottom_solid_layers > 0
            ? fill
            : clip::diff_ex(fill, P.bottom_solid_layers > 0 ? covered_below : fill);
    const ExPolygons solid = clip::union_ex([&] {
      ExPolygons u = top;
      u.insert(u.end(), bottom.begin(), bottom.end());
      return u;
    }());
    const ExPolygons exposed =
        i + 1 < n ? clip::intersection_ex(top, clip::diff_ex(fill, covers(i + 1))) : top;
    const ExPolygons solid_inner = clip::diff_ex(solid, exposed);
    const ExPolygons sparse = clip::diff_ex(fill, solid);

    // Perimeters per island: inner rings first, the external one last.
    std::vector<std::vector<ExtrusionPath>> groups;
    for (const auto& rings : reg[i].loops) {
      std::vector<ExtrusionPath> g;
      for (int r = static_cast<int>(rings.size()) - 1; r >= 0; --r)
        for (const Polygon& loop : rings[r])
          g.push_back(make_path(
              r == 0 ? ExtrusionRole::external_perimeter : ExtrusionRole::perimeter,
              r == 0 ? we : wp, speed(r == 0 ? P.external_perimeter_speed : P.perimeter_speed),
              loop, true, z, h));
      if (!g.empty()) groups.push_back(std::move(g));
    }
    std::vector<ExtrusionPath> islands_paths;
    const double angle = P.fill_angle + (i % 2 ? 90.0 : 0.0);
    // Solid fill (spacing s) is fitted to each island; a line spaced d instead of `spacing` is
    // w + d − spacing wide (on the global grid d is `spacing`).
    auto add_lines = [&](const ExPolygons& region, ExtrusionRole role, double spacing, double ang,
                         double v) {
      for (const auto& l : paths::infill_lines(region, ang, spacing, s, spacing == s))
        islands_paths.push_back(
            make_path(role, w + (l.spacing - spacing), speed(v), l.line, false, z, h));
    };
    add_lines(exposed, ExtrusionRole::top_solid_infill, s, angle, P.top_solid_infill_speed);
    add_lines(solid_inner, ExtrusionRole::solid_infill, s, angle, P.solid_infill_speed);
    if (P.fill_density > 0) {
      if (P.fill_density >= 0.999) {
        add_lines(sparse, ExtrusionRole::internal_infill, s, angle, P.infill_speed);
      } else if (P.fill_pattern == InfillPattern::grid) {
        add_lines(sparse, ExtrusionRole::internal_infill, 2 * s / P.fill_density, P.fill_angle,
                  P.infill_speed);
        add_lines(sparse, ExtrusionRole::internal_infill, 2 * s / P.fill_density, P.fill_angle + 90,
                  P.infill_speed);
      } else {
        add_lines(sparse, ExtrusionRole::internal_infill, s / P.fill_density, angle,
                  P.infill_speed);
      }
    }
    // Perimeters before infill; islands visited nearest first, each loop starting where the
    // nozzle is.
    std::vector<ExtrusionPath> perims, fills = std::move(islands_paths);
    Vec2 at = Vec2::Zero();
    std::vector<char> done(groups.size(), 0);
    for (std::size_t gcount = 0; gcount < groups.size(); ++gcount) {
      double best = 1e300;
      std::size_t bi = 0;
      for (std::size_t g = 0; g < groups.size(); ++g) {
        if (done[g]) continue;
        for (const Vec3& q : groups[g].front().points)
          if ((q.head<2>() - at).squaredNorm() < best)
            best = (q.head<2>() - at).squaredNorm(), bi = g;
      }
      done[bi] = 1;
      for (auto& path : groups[bi]) {
        std::vector<ExtrusionPath> one{std::move(path)};
        paths::order_paths(one, at);
        at = one[0].points.back().head<2>();
        perims.push_back(std::move(one[0]));
      }
    }
    paths::order_paths(fills, at);
    if (i == 0 && P.skirts > 0 && !L.islands.empty()) {
      ExPolygons ring = clip::offset_ex(clip::union_ex(L.islands), P.skirt_distance + 0.5 * w);
      for (int k = 0; k < P.skirts && !ring.empty(); ++k) {
        for (const ExPolygon& e : ring)
          T.paths.push_back(
              make_path(ExtrusionRole::skirt, w, P.first_layer_speed, e.contour, true, z, h));
        ring = clip::offset_ex(ring, s);
      }
    }
    for (auto& p : perims) T.paths.push_back(std::move(p));
    for (auto& p : fills) T.paths.push_back(std::move(p));
  });
  if (stop) return Error{Status::cancelled, "cancelled"};
  ctx.progress("toolpaths", 1.0);
  return out;
}

}  // namespace nonplanar
