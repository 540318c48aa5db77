// Strict G-code reader for check, for mapping foreign G-code and for the writer's own
// custom blocks.
#include <charconv>
#include <cmath>
#include <string>

#include "io/mesh_buffer.hpp"
#include "nonplanar/gcode.hpp"

namespace nonplanar {

Expected<std::vector<PrintMove>> read_gcode_moves(std::string_view text) {
  std::vector<PrintMove> moves;
  Vec3 pos(0, 0, 0);
  double e = 0, width = 0.45;
  bool rel_e = false, rel_xyz = false;
  std::string type;
  int layer = -1, line = 0;
  std::size_t start = 0;
  auto fail = [&](const std::string& why) {
    return Error{Status::parse_error, "line " + std::to_string(line) + ": " + why};
  };
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view l = text.substr(start, end - start);
    start = end + 1;
    ++line;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    const std::size_t semi = l.find(';');
    if (semi != std::string_view::npos) {
      const std::string_view c = l.substr(semi);
      if (c.rfind(";TYPE:", 0) == 0)
        type = std::string(c.substr(6));
      else if (c.rfind(";LAYER_CHANGE", 0) == 0)
        ++layer;
      else if (c.rfind(";WIDTH:", 0) == 0) {
        if (auto w = io::parse_double(c.substr(7)); w && *w > 0) width = *w;
      }
      l = l.substr(0, semi);
    }
    io::Tokenizer tok(l);
    const std::string_view cmd = tok.next();
    if (cmd.empty()) continue;
    const char kind = static_cast<char>(std::toupper(static_cast<unsigned char>(cmd[0])));
    const auto num = io::parse_int(cmd.substr(1));
    if ((kind != 'G' && kind != 'M' && kind != 'T') || (!num && kind != 'T'))
      return fail("'" + std::string(cmd.substr(0, 20)) + "' is not a G-code command");
    if (kind == 'T') continue;  // tool change: single extruder here
    if (kind == 'M') {
      if (*num == 82) rel_e = false;
      if (*num == 83) rel_e = true;
      continue;
    }
    switch (*num) {
      case 0:
      case 1: {
        PrintMove m;
        m.from = pos;
        Vec3 to = pos;
        bool has_e = false;
        double ev = 0;
        for (std::string_view w = tok.next(); !w.empty(); w = tok.next()) {
          const char a = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
          const auto v = io::parse_double(w.substr(1));
          if (!v) return fail("bad number in '" + std::string(w.substr(0, 30)) + "'");
          switch (a) {
            case 'X':
              to.x() = rel_xyz ? to.x() + *v : *v;
              break;
            case 'Y':
              to.y() = rel_xyz ? to.y() + *v : *v;
              break;
            case 'Z':
              to.z() = rel_xyz ? to.z() + *v : *v;
              break;
            case 'E':
              has_e = true, ev = *v;
              break;
            case 'F':
              break;
            default:
              return fail("unknown word '" + std::string(w.substr(0, 20)) + "' in a move");
          }
        }
        if (has_e) {
          // G91 makes E relative too (Klipper, RepRapFirmware, Marlin 1, PrusaSlicer's
          // G-code viewer), as M83 does.
          const bool rel = rel_e || rel_xyz;
          m.filament = rel ? ev : ev - e;
          e = rel ? e + ev : ev;
        }
        m.to = to;
        m.extruding = m.filament > 0 && (to.head<2>() - pos.head<2>()).norm() > 1e-9;
        m.type = type, m.layer = layer, m.width = width, m.line = line;
        moves.push_back(std::move(m));
        pos = to;
        break;
      }
      case 92:
        for (std::string_view w = tok.next(); !w.empty(); w = tok.next()) {
          const auto v = io::parse_double(w.substr(1));
          if (!v) return fail("bad number in G92");
          const char a = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
          if (a == 'E')
            e = *v;
          else if (a == 'X')
            pos.x() = *v;
          else if (a == 'Y')
            pos.y() = *v;
          else if (a == 'Z')
            pos.z() = *v;
        }
        break;
      case 90:
        rel_xyz = false;
        break;
      case 91:
        rel_xyz = true;
        break;
      case 2:
      case 3:
        return fail("arc moves (G2/G3) are not supported; turn arc fitting off");
      case 20:
        return fail("inch units (G20) are not supported");
      case 4:
      case 10:
      case 11:
      case 17:
      case 21:
      case 28:
      case 29:
      case 80:
      case 94:
        break;
      default:
        return fail("unknown G-code G" + std::to_string(*num));
    }
  }
  return moves;
}

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
