#include "core/section_plot.hpp"

#include <algorithm>
#include <cmath>

namespace nonplanar::core {
namespace {

// A round tick step giving about 8 ticks over `range`.
double nice_step(double range) {
  const double raw = range / 8;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

}  // namespace

SectionFrame::SectionFrame(double s_lo, double s_hi, double z_top, double width_px)
    : s0(s_lo), s1(s_hi), z1(z_top), scale(width_px / std::max(s_hi - s_lo, 1e-6)) {}

std::vector<std::array<double, 4>> section_outline(const TriangleMesh& mesh, char axis,
                                                   double value) {
  const int hs = axis == 'x' ? 1 : 0;  // s is y in a plane x = value
  std::vector<std::array<double, 4>> outline;
  for (const auto& f : mesh.faces) {
    std::vector<std::pair<double, double>> cut;
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = mesh.vertices[static_cast<std::size_t>(f[static_cast<std::size_t>(k)])];
      const Vec3& b =
          mesh.vertices[static_cast<std::size_t>(f[static_cast<std::size_t>((k + 1) % 3)])];
      const double da = a[1 - hs] - value, db = b[1 - hs] - value;
      if ((da < 0) != (db < 0)) {
        const Vec3 p = a + da / (da - db) * (b - a);
        cut.emplace_back(p[hs], p.z());
      }
    }
    if (cut.size() == 2)
      outline.push_back({cut[0].first, cut[0].second, cut[1].first, cut[1].second});
  }
  return outline;
}

void svg_begin(std::ostream& svg, const SectionFrame& f, const std::string& title, char s_name) {
  svg.precision(2);
  svg << std::fixed;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << f.width() << "\" height=\""
      << f.height() << "\" viewBox=\"0 0 " << f.width() << ' ' << f.height()
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg << "<text x=\"" << f.left << "\" y=\"22\" font-size=\"15\">" << title << "</text>\n";
  const double step_s = nice_step(f.s1 - f.s0), step_z = nice_step(std::max(f.z1, 1.0));
  svg << "<g stroke=\"#444\" stroke-width=\"1\">\n<line x1=\"" << f.X(f.s0) << "\" y1=\"" << f.Y(0)
      << "\" x2=\"" << f.X(f.s1) << "\" y2=\"" << f.Y(0) << "\"/>\n<line x1=\"" << f.X(f.s0)
      << "\" y1=\"" << f.Y(0) << "\" x2=\"" << f.X(f.s0) << "\" y2=\"" << f.Y(f.z1) << "\"/>\n";
  for (double t = std::ceil(f.s0 / step_s) * step_s; t <= f.s1 + 1e-9; t += step_s)
    svg << "<line x1=\"" << f.X(t) << "\" y1=\"" << f.Y(0) << "\" x2=\"" << f.X(t) << "\" y2=\""
        << f.Y(0) + 5 << "\"/>\n";
  for (double t = 0; t <= f.z1 + 1e-9; t += step_z)
    svg << "<line x1=\"" << f.X(f.s0) - 5 << "\" y1=\"" << f.Y(t) << "\" x2=\"" << f.X(f.s0)
        << "\" y2=\"" << f.Y(t) << "\"/>\n";
  svg << "</g>\n<g fill=\"#222\">\n";
  for (double t = std::ceil(f.s0 / step_s) * step_s; t <= f.s1 + 1e-9; t += step_s)
    svg << "<text x=\"" << f.X(t) << "\" y=\"" << f.Y(0) + 18 << "\" text-anchor=\"middle\">" << t
        << "</text>\n";
  for (double t = 0; t <= f.z1 + 1e-9; t += step_z)
    svg << "<text x=\"" << f.X(f.s0) - 8 << "\" y=\"" << f.Y(t) + 4 << "\" text-anchor=\"end\">"
        << t << "</text>\n";
  svg << "<text x=\"" << f.X(0.5 * (f.s0 + f.s1)) << "\" y=\"" << f.Y(0) + 36
      << "\" text-anchor=\"middle\">" << s_name << " (mm)</text>\n<text x=\"18\" y=\""
      << f.Y(f.z1 / 2) << "\" transform=\"rotate(-90 18 " << f.Y(f.z1 / 2)
      << ")\" text-anchor=\"middle\">z (mm)</text>\n</g>\n";
}

void svg_end(std::ostream& svg, const SectionFrame& f,
             const std::vector<std::array<double, 4>>& outline) {
  svg << "<g stroke=\"black\" stroke-width=\"1.6\">\n";
  for (const auto& o : outline)
    svg << "<line x1=\"" << f.X(o[0]) << "\" y1=\"" << f.Y(o[1]) << "\" x2=\"" << f.X(o[2])
        << "\" y2=\"" << f.Y(o[3]) << "\"/>\n";
  svg << "</g>\n</svg>\n";
}

}  // namespace nonplanar::core
