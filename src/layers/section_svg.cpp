// The cross-section picture: part outline, layer boundaries inside the material, axes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/column_caster.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar {
namespace {

struct Mapper {  // section coordinates (s, z) in mm → SVG pixels
  double s0, z1, scale, left, top;
  double X(double s) const { return left + (s - s0) * scale; }
  double Y(double z) const { return top + (z1 - z) * scale; }
};

double nice_step(double range) {
  const double raw = range / 8;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

}  // namespace

Expected<void> write_section_svg(const std::filesystem::path& file, const TriangleMesh& mesh,
                                 const LayerPlan& plan, char axis, double value) {
  if (axis != 'x' && axis != 'y')
    return Error{Status::invalid_argument, "section axis: must be x or y"};
  const LayerField& F = *plan.field;
  const BoundingBox box = bounding_box(mesh);
  const int hs = axis == 'x' ? 1 : 0;  // horizontal coordinate of the picture
  if (value < box.min[1 - hs] || value > box.max[1 - hs])
    return Error{Status::invalid_argument, std::string("section: ") + axis + " = " +
                                               std::to_string(value) + " misses the part (" +
                                               std::to_string(box.min[1 - hs]) + " to " +
                                               std::to_string(box.max[1 - hs]) + ")"};
  auto point = [&](double s) { return axis == 'x' ? Vec2(value, s) : Vec2(s, value); };

  // Part outline: the plane's cut through every triangle it crosses.
  std::vector<std::array<double, 4>> outline;
  for (const auto& f : mesh.faces) {
    std::vector<Vec2> cut;
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = mesh.vertices[f[k]];
      const Vec3& b = mesh.vertices[f[(k + 1) % 3]];
      const double da = a[1 - hs] - value, db = b[1 - hs] - value;
      if ((da < 0) != (db < 0)) {
        const Vec3 p = a + da / (da - db) * (b - a);
        cut.emplace_back(p[hs], p.z());
      }
    }
    if (cut.size() == 2) outline.push_back({cut[0].x(), cut[0].y(), cut[1].x(), cut[1].y()});
  }
  if (outline.empty()) return Error{Status::invalid_argument, "section: the plane misses the part"};

  const double s0 = box.min[hs], s1 = box.max[hs], z1 = box.max.z();
  const double width_px = 1100, scale = width_px / std::max(s1 - s0, 1e-6);
  const Mapper M{s0, z1, scale, 70, 50};
  const double height_px = z1 * scale;

  // Layer boundaries column by column; curved where they leave the planar height.
  const ColumnCaster columns(mesh);
  const double ds = std::max((s1 - s0) / 1500.0, 0.02);
  const int kmax = static_cast<int>(std::ceil(F.t_of_zeta(z1 + 5))) + 2;
  std::ostringstream planar_path, curved_path;
  planar_path.precision(2);
  curved_path.precision(2);
  planar_path << std::fixed;
  curved_path << std::fixed;
  std::vector<double> prev_z(kmax + 1, NAN);
  std::vector<char> prev_curved(kmax + 1, 0);
  int curved_layers_seen = 0;
  std::vector<char> layer_is_curved(kmax + 1, 0);
  // A boundary is drawn as curved where a band reaches the column and its index lies in a
  // stack (it may cross its planar height there, as on a saddle, and still be curved).
  auto in_stack = [&](int k) {
    for (const LayerStack& st : plan.stacks)
      if (k > st.T_bottom + 0.5 && k <= st.T_bottom + st.layers + 0.5) return true;
    return false;
  };
  for (double s = s0; s <= s1 + 1e-9; s += ds) {
    const Vec2 xy = point(s);
    const auto iv = columns.intervals(xy.x(), xy.y());
    const bool planar = F.planar_at(xy.x(), xy.y());
    for (int k = 1; k <= kmax; ++k) {
      double z = NAN;
      const double zp = F.zeta(k);
      const double zk = planar ? zp : F.z_at(xy.x(), xy.y(), k);
      for (const auto& [lo, hi] : iv)
        if (zk >= lo - 1e-6 && zk <= hi + 1e-6) z = zk;
      const bool curved = !planar && (in_stack(k) || std::abs(zk - zp) > 0.005);
      if (!std::isnan(z) && !std::isnan(prev_z[k])) {
        std::ostringstream& out = (curved || prev_curved[k]) ? curved_path : planar_path;
        out << 'M' << M.X(s - ds) << ',' << M.Y(prev_z[k]) << 'L' << M.X(s) << ',' << M.Y(z);
        if (curved) layer_is_curved[k] = 1;
      }
      prev_z[k] = z;
      prev_curved[k] = curved;
    }
  }
  for (char c : layer_is_curved) curved_layers_seen += c;

  std::ostringstream svg;
  svg.precision(2);
  svg << std::fixed;
  const double W = width_px + 110, H = height_px + 110;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
      << "\" viewBox=\"0 0 " << W << ' ' << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg << "<text x=\"" << M.left << "\" y=\"22\" font-size=\"15\">Section at " << axis << " = "
      << value << " mm: " << curved_layers_seen << " curved layer boundaries (orange), "
      << plan.stacks.size() << " curved band" << (plan.stacks.size() == 1 ? "" : "s") << ", "
      << plan.fallbacks.size() << " patch" << (plan.fallbacks.size() == 1 ? "" : "es")
      << " kept planar</text>\n";
  // Axes with ticks in mm.
  const double step_s = nice_step(s1 - s0), step_z = nice_step(std::max(z1, 1.0));
  svg << "<g stroke=\"#444\" stroke-width=\"1\">\n<line x1=\"" << M.X(s0) << "\" y1=\"" << M.Y(0)
      << "\" x2=\"" << M.X(s1) << "\" y2=\"" << M.Y(0) << "\"/>\n<line x1=\"" << M.X(s0)
      << "\" y1=\"" << M.Y(0) << "\" x2=\"" << M.X(s0) << "\" y2=\"" << M.Y(z1) << "\"/>\n";
  for (double t = std::ceil(s0 / step_s) * step_s; t <= s1 + 1e-9; t += step_s)
    svg << "<line x1=\"" << M.X(t) << "\" y1=\"" << M.Y(0) << "\" x2=\"" << M.X(t) << "\" y2=\""
        << M.Y(0) + 5 << "\"/>\n";
  for (double t = 0; t <= z1 + 1e-9; t += step_z)
    svg << "<line x1=\"" << M.X(s0) - 5 << "\" y1=\"" << M.Y(t) << "\" x2=\"" << M.X(s0)
        << "\" y2=\"" << M.Y(t) << "\"/>\n";
  svg << "</g>\n<g fill=\"#222\">\n";
  for (double t = std::ceil(s0 / step_s) * step_s; t <= s1 + 1e-9; t += step_s)
    svg << "<text x=\"" << M.X(t) << "\" y=\"" << M.Y(0) + 18 << "\" text-anchor=\"middle\">" << t
        << "</text>\n";
  for (double t = 0; t <= z1 + 1e-9; t += step_z)
    svg << "<text x=\"" << M.X(s0) - 8 << "\" y=\"" << M.Y(t) + 4 << "\" text-anchor=\"end\">" << t
        << "</text>\n";
  svg << "<text x=\"" << M.X(0.5 * (s0 + s1)) << "\" y=\"" << M.Y(0) + 36
      << "\" text-anchor=\"middle\">" << (hs == 1 ? 'y' : 'x')
      << " (mm)</text>\n<text x=\"18\" y=\"" << M.Y(z1 / 2) << "\" transform=\"rotate(-90 18 "
      << M.Y(z1 / 2) << ")\" text-anchor=\"middle\">z (mm)</text>\n</g>\n";
  svg << "<path fill=\"none\" stroke=\"#bbb\" stroke-width=\"0.6\" d=\"" << planar_path.str()
      << "\"/>\n<path fill=\"none\" stroke=\"#e8700a\" stroke-width=\"1.1\" d=\""
      << curved_path.str() << "\"/>\n<g stroke=\"black\" stroke-width=\"1.6\">\n";
  for (const auto& o : outline)
    svg << "<line x1=\"" << M.X(o[0]) << "\" y1=\"" << M.Y(o[1]) << "\" x2=\"" << M.X(o[2])
        << "\" y2=\"" << M.Y(o[3]) << "\"/>\n";
  svg << "</g>\n</svg>\n";
  const std::string text = svg.str();
  return write_file_atomically(file, [&](std::ostream& out) {
    out << text;
    return bool(out);
  });
}

}  // namespace nonplanar
