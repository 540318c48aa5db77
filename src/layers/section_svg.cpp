// The cross-section picture: part outline, layer boundaries inside the material, axes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/column_caster.hpp"
#include "core/section_plot.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar {

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
  const auto outline = core::section_outline(mesh, axis, value);
  if (outline.empty()) return Error{Status::invalid_argument, "section: the plane misses the part"};

  const double s0 = box.min[hs], s1 = box.max[hs], z1 = box.max.z();
  const core::SectionFrame M(s0, s1, z1, 1100);

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

  std::ostringstream svg, title;
  title << "Section at " << axis << " = " << std::fixed << std::setprecision(2) << value
        << " mm: " << curved_layers_seen << " curved layer boundaries (orange), "
        << plan.stacks.size() << " curved band" << (plan.stacks.size() == 1 ? "" : "s") << ", "
        << plan.fallbacks.size() << " patch" << (plan.fallbacks.size() == 1 ? "" : "es")
        << " kept planar";
  core::svg_begin(svg, M, title.str(), hs == 1 ? 'y' : 'x');
  svg << "<path fill=\"none\" stroke=\"#bbb\" stroke-width=\"0.6\" d=\"" << planar_path.str()
      << "\"/>\n<path fill=\"none\" stroke=\"#e8700a\" stroke-width=\"1.1\" d=\""
      << curved_path.str() << "\"/>\n";
  core::svg_end(svg, M, outline);
  const std::string text = svg.str();
  return write_file_atomically(file, [&](std::ostream& out) {
    out << text;
    return bool(out);
  });
}

}  // namespace nonplanar
