// G-code → the preview's per-segment buffers (preview.hpp). Notation there: w bead width,
// h bead height, A the bead's section, c = 1 − π/4.
#include <algorithm>
#include <cmath>

#include "nonplanar/preview.hpp"

namespace nonplanar {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The bead height whose rounded-rectangle section (w − h)·h + π·h²/4 = A, the smaller root of
// c·h² − w·h + A = 0; capped at w, where the model stops being a bead.
double bead_height(double section, double width) {
  constexpr double c = 1.0 - kPi / 4.0;
  const double disc = width * width - 4 * c * section;
  if (disc <= 0) return width;
  return std::min(width, (width - std::sqrt(disc)) / (2 * c));
}

std::uint16_t quantise(double v, double lo, double size) {
  if (size <= 0) return 0;
  const double q = std::round((v - lo) / size * 65535.0);
  return static_cast<std::uint16_t>(std::clamp(q, 0.0, 65535.0));
}

std::uint8_t byte_of(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
}

bool kept(const GcodeMove& m, const PreviewParams& p) {
  if ((m.to - m.from).squaredNorm() < 1e-18) return false;  // E-only, F-only
  return p.travels || m.extruding();
}

// Index of a ;TYPE: name, added on first use (at most 256 names; later ones share the last).
std::uint8_t role_index(std::string_view type, std::vector<std::string>& names) {
  const std::string_view name = type.empty() ? std::string_view("Custom") : type;
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<std::uint8_t>(i);
  if (names.size() == 256) return 255;
  names.emplace_back(name);
  return static_cast<std::uint8_t>(names.size() - 1);
}

// Per layer: the extrusions' lowest and highest z.
void layer_spans(const GcodeProgram& program, int layers, std::vector<double>& lo,
                 std::vector<double>& hi) {
  lo.assign(static_cast<std::size_t>(layers), 1e300);
  hi.assign(static_cast<std::size_t>(layers), -1e300);
  for (const GcodeMove& m : program.moves) {
    // The print's own extrusions: a purge line in the start G-code is not a layer's.
    if (!m.extruding() || m.layer < 0 || m.line < 1 ||
        !program.in_print(static_cast<std::size_t>(m.line - 1)))
      continue;
    const auto k = static_cast<std::size_t>(std::clamp(m.layer, 0, layers - 1));
    lo[k] = std::min({lo[k], m.from.z(), m.to.z()});
    hi[k] = std::max({hi[k], m.from.z(), m.to.z()});
  }
}

}  // namespace

PreviewBuffers preview_buffers(const GcodeProgram& program, const std::vector<double>& line_time,
                               const PreviewParams& params) {
  PreviewBuffers b;
  for (const GcodeMove& m : program.moves) {
    b.filament_mm += m.de;
    if (!kept(m, params)) continue;
    b.box.extend(m.from);
    b.box.extend(m.to);
  }
  if (b.box.empty()) return b;
  b.layers = std::max(1, program.lines.empty() ? 0 : program.lines.back().layer + 1);
  b.seconds = line_time.empty() ? 0.0 : line_time.back();
  std::vector<double> lo, hi;
  layer_spans(program, b.layers, lo, hi);
  std::vector<bool> curved(lo.size());
  b.layer_z.resize(lo.size());
  for (std::size_t k = 0; k < lo.size(); ++k) {
    curved[k] = hi[k] - lo[k] > params.curved_span;
    b.curved_layers += curved[k] ? 1 : 0;
    // A layer with no extrusion (a last, empty one) is at its ;Z:, else the one below's.
    const double z = lo[k] <= hi[k]               ? lo[k]
                     : k < program.layer_z.size() ? program.layer_z[k]
                     : k > 0                      ? b.layer_z[k - 1]
                                                  : 0.0;
    b.layer_z[k] = static_cast<float>(z);
  }
  const double area = kPi * params.filament_diameter * params.filament_diameter / 4;
  const Vec3 size = b.box.size();
  for (const GcodeMove& m : program.moves) {
    if (!kept(m, params)) continue;
    for (const Vec3* p : {&m.from, &m.to})
      for (int a = 0; a < 3; ++a) b.ends.push_back(quantise((*p)[a], b.box.min[a], size[a]));
    const int k = std::clamp(m.layer, 0, b.layers - 1);
    b.layer.push_back(static_cast<std::uint16_t>(std::min(k, 65535)));
    b.role.push_back(role_index(m.type, b.role_names));
    const bool extrusion = m.extruding();
    b.flags.push_back(static_cast<std::uint8_t>(
        (extrusion ? 0 : PreviewBuffers::kTravel) |
        (curved[static_cast<std::size_t>(k)] ? PreviewBuffers::kCurvedLayer : 0)));
    const Vec3 d = m.to - m.from;
    const double len = d.norm(), run = d.head<2>().norm();
    // E has 5 decimals: on a piece shorter than 0.05 mm (a curved path's resampling leaves
    // some) its section is noise, so it takes the bead's before it.
    const bool short_piece = len < 0.05 && !b.thickness.empty() && b.thickness.back() > 0;
    const double h = extrusion ? bead_height(m.de * area / len, m.width) : 0.0;
    b.thickness.push_back(extrusion && short_piece ? b.thickness.back() : byte_of(h / 0.005));
    b.width.push_back(byte_of(m.width / 0.01));
    b.slope.push_back(byte_of(std::atan2(std::abs(d.z()), run) * 180 / kPi));
    const auto line = static_cast<std::size_t>(std::max(m.line, 0));
    b.time.push_back(line < line_time.size() ? static_cast<float>(line_time[line]) : 0.0f);
  }
  return b;
}

}  // namespace nonplanar
