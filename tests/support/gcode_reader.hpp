// A strict, test-side G-code reader: it knows the commands nonplanar and PrusaSlicer emit,
// refuses anything else, and turns the file into moves with their feature type and layer.
#pragma once

#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar::test {

struct Move {
  Vec3 from, to;
  double de = 0;        // filament pushed (mm); negative for retractions
  bool travel = false;  // no extrusion
  std::string type;     // ;TYPE: in force
  int layer = -1;       // index of ;LAYER_CHANGE seen so far
  double layer_z = 0, height = 0;
  int line = 0;
};

struct Program {
  std::vector<Move> moves;
  std::vector<double> layer_z;  // ;Z: per layer
  std::string error;            // first problem, empty when clean
};

inline Program read_gcode(const std::string& text) {
  Program prog;
  std::istringstream in(text);
  std::string l;
  Vec3 pos = Vec3::Zero();
  double e = 0, z_mark = 0, h_mark = 0;
  bool relative_e = false, relative_xyz = false;
  std::string type;
  int layer = -1, n = 0;
  while (std::getline(in, l)) {
    ++n;
    if (l.rfind(";TYPE:", 0) == 0) type = l.substr(6);
    if (l.rfind(";LAYER_CHANGE", 0) == 0) ++layer;
    if (l.rfind(";Z:", 0) == 0) prog.layer_z.push_back(z_mark = std::stod(l.substr(3)));
    if (l.rfind(";HEIGHT:", 0) == 0) h_mark = std::stod(l.substr(8));
    const std::string code = l.substr(0, l.find(';'));
    std::istringstream w(code);
    std::string cmd;
    if (!(w >> cmd)) continue;
    if (cmd == "M82")
      relative_e = false;
    else if (cmd == "M83")
      relative_e = true;
    else if (cmd == "G90")
      relative_xyz = false;
    else if (cmd == "G91")
      relative_xyz = true;
    else if (cmd == "G92") {
      std::string a;
      while (w >> a)
        if (a[0] == 'E') e = std::stod(a.substr(1));
    } else if (cmd == "G0" || cmd == "G1") {
      Vec3 to = relative_xyz ? pos : pos;
      std::optional<double> ev;
      std::string a;
      while (w >> a) {
        const double v = std::stod(a.substr(1));
        if (!std::isfinite(v))
          prog.error = prog.error.empty() ? "non-finite at line " + std::to_string(n) : prog.error;
        switch (a[0]) {
          case 'X':
            to.x() = relative_xyz ? pos.x() + v : v;
            break;
          case 'Y':
            to.y() = relative_xyz ? pos.y() + v : v;
            break;
          case 'Z':
            to.z() = relative_xyz ? pos.z() + v : v;
            break;
          case 'E':
            ev = v;
            break;
          case 'F':
            break;
          default:
            if (prog.error.empty())
              prog.error = "unknown word " + a + " at line " + std::to_string(n);
        }
      }
      Move m;
      m.from = pos, m.to = to, m.type = type, m.layer = layer, m.layer_z = z_mark;
      m.height = h_mark, m.line = n;
      if (ev) {
        m.de = relative_e ? *ev : *ev - e;
        e = relative_e ? e + *ev : *ev;
      }
      // An E move without XY motion (a retraction or its restore) deposits nothing.
      const bool moves_xy = (to.head<2>() - pos.head<2>()).norm() > 1e-9;
      m.travel = !(m.de > 0 && moves_xy);
      prog.moves.push_back(m);
      pos = to;
    } else if (cmd == "G4" || cmd == "G21" || cmd == "G28" || cmd == "M84" || cmd == "M104" ||
               cmd == "M106" || cmd == "M107" || cmd == "M109" || cmd == "M140" || cmd == "M190" ||
               cmd == "M486" || cmd.rfind("EXCLUDE_OBJECT_", 0) == 0) {
      // known, no motion (M486 and EXCLUDE_OBJECT_*: object labels)
    } else if (prog.error.empty()) {
      prog.error = "unknown command " + cmd + " at line " + std::to_string(n);
    }
  }
  return prog;
}

}  // namespace nonplanar::test
