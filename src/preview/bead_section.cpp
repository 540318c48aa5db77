// The printed beads in a vertical plane (preview.hpp, bead_section_svg). Notation as in
// core/section_plot.hpp: the plane x = value or y = value, s the picture's horizontal axis.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/section_plot.hpp"
#include "nonplanar/preview.hpp"

namespace nonplanar {
namespace {

struct Bead {
  double s, z, w, h;  ///< centre line's crossing, the bead's width in the plane and height, mm
  bool curved;
  int layer;
};

// Every extrusion segment that crosses the plane: where, and its bead's section there. A
// segment that meets the plane at angle φ in XY cuts its bead over w / sin φ (at most 4 w).
std::vector<Bead> crossings(const PreviewBuffers& b, int hs, double value) {
  std::vector<Bead> out;
  const Vec3 lo = b.box.min, size = b.box.size();
  auto at = [&](std::size_t i, int k) {
    Vec3 p;
    for (int a = 0; a < 3; ++a)
      p[a] = lo[a] + b.ends[6 * i + static_cast<std::size_t>(3 * k + a)] / 65535.0 * size[a];
    return p;
  };
  // Not the start G-code's purge line (before any ;TYPE: or under "Custom"), nor the skirt.
  std::vector<char> shown(b.role_names.size(), 1);
  for (std::size_t r = 0; r < b.role_names.size(); ++r)
    shown[r] = b.role_names[r] != "Custom" && b.role_names[r].find("kirt") == std::string::npos;
  for (std::size_t i = 0; i < b.segments(); ++i) {
    if ((b.flags[i] & PreviewBuffers::kTravel) || !shown[b.role[i]]) continue;
    const Vec3 p = at(i, 0), q = at(i, 1);
    const double dp = p[1 - hs] - value, dq = q[1 - hs] - value;
    if ((dp < 0) == (dq < 0) || dp == dq) continue;
    const Vec3 c = p + dp / (dp - dq) * (q - p);
    const double run = (q - p).head<2>().norm();
    const double across = run > 0 ? std::abs(dp - dq) / run : 1;  // sin φ
    const double w = b.width[i] * 0.01;
    out.push_back({c[hs], c.z(), std::min(4 * w, w / std::max(across, 1e-9)),
                   b.thickness[i] * 0.005, (b.flags[i] & PreviewBuffers::kCurvedLayer) != 0,
                   b.layer[i]});
  }
  return out;
}

}  // namespace

Expected<std::string> bead_section_svg(const PreviewBuffers& b, const TriangleMesh* mesh, char axis,
                                       double value) {
  if (axis != 'x' && axis != 'y')
    return Error{Status::invalid_argument, "section axis: must be x or y"};
  const int hs = axis == 'x' ? 1 : 0;
  const std::vector<Bead> beads = crossings(b, hs, value);
  if (beads.empty()) {
    std::ostringstream why;
    why << "section: no extrusion crosses " << axis << " = " << value << " mm";
    return Error{Status::invalid_argument, why.str()};
  }
  double s0 = 1e300, s1 = -1e300, z1 = 0;
  for (const Bead& d : beads)
    s0 = std::min(s0, d.s - d.w), s1 = std::max(s1, d.s + d.w), z1 = std::max(z1, d.z);
  std::vector<std::array<double, 4>> outline;
  if (mesh) {
    outline = core::section_outline(*mesh, axis, value);
    for (const auto& o : outline)
      s0 = std::min({s0, o[0], o[2]}), s1 = std::max({s1, o[0], o[2]}),
      z1 = std::max({z1, o[1], o[3]});
  }
  const core::SectionFrame f(s0 - 1, s1 + 1, z1 + 0.5, 1400);
  int curved = 0, planar = 0;
  std::vector<char> seen(static_cast<std::size_t>(std::max(b.layers, 1)), 0);
  for (const Bead& d : beads) {
    char& s = seen[static_cast<std::size_t>(std::clamp(d.layer, 0, b.layers - 1))];
    if (!s) s = 1, (d.curved ? curved : planar) += 1;
  }
  std::ostringstream svg, title;
  title << "Beads crossing " << axis << " = " << std::fixed << std::setprecision(2) << value
        << " mm: " << curved << " curved layers (orange), " << planar << " planar (blue)";
  core::svg_begin(svg, f, title.str(), hs == 1 ? 'y' : 'x');
  // Each bead as its section: a rectangle w wide, h tall, its top at the centre line's z;
  // alternate layers lighter, so each layer's run shows.
  svg << "<g stroke=\"none\">\n";
  for (const Bead& d : beads) {
    const char* fill =
        d.curved ? (d.layer % 2 ? "#f4a261" : "#d9651b") : (d.layer % 2 ? "#9bbbe0" : "#3f6fb0");
    svg << "<rect x=\"" << f.X(d.s - 0.5 * d.w) << "\" y=\"" << f.Y(d.z) << "\" width=\""
        << d.w * f.scale << "\" height=\"" << std::max(d.h, 0.01) * f.scale << "\" fill=\"" << fill
        << "\"/>\n";
  }
  svg << "</g>\n";
  core::svg_end(svg, f, outline);
  return svg.str();
}

}  // namespace nonplanar
