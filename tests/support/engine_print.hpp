// Tests of the engine route: whether PrusaSlicer is installed, and what a program from it
// prints, as far as its runs repeat themselves.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace nonplanar::test {

/// Whether prusa-slicer is on PATH (scripts/test.sh installs it; tests skip without it).
inline bool have_prusaslicer() {
  return std::system("command -v prusa-slicer >/dev/null 2>&1") == 0;
}

// What two runs of PrusaSlicer on one mesh agree on (it is not byte for byte the same from run
// to run: its threads): the layers' heights, the filament and the box of what it extrudes.
struct Made {
  std::vector<std::string> layers;
  double filament = 0;
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
};
inline Made made(const std::string& g) {
  Made m;
  std::istringstream in(g);
  double e = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(";Z:", 0) == 0) m.layers.push_back(line);
    if (line.rfind("; filament used [mm] = ", 0) == 0) m.filament = std::stod(line.substr(23));
    if (line.rfind("G92 E0", 0) == 0) e = 0;
    if (line.rfind("G1 ", 0) != 0) continue;
    const auto x = line.find(" X"), y = line.find(" Y"), ee = line.find(" E");
    if (ee == std::string::npos || x == std::string::npos || y == std::string::npos) continue;
    const double en = std::stod(line.substr(ee + 2));
    if (en > e) {
      const double px = std::stod(line.substr(x + 2)), py = std::stod(line.substr(y + 2));
      m.x0 = std::min(m.x0, px), m.x1 = std::max(m.x1, px);
      m.y0 = std::min(m.y0, py), m.y1 = std::max(m.y1, py);
    }
    e = en;
  }
  return m;
}
inline void expect_same_print(const std::string& a, const std::string& b) {
  const Made p = made(a), q = made(b);
  EXPECT_GT(p.layers.size(), 10u);
  EXPECT_EQ(p.layers, q.layers);
  EXPECT_NEAR(p.filament, q.filament, 0.002 * q.filament);
  EXPECT_NEAR(p.x0, q.x0, 0.01);
  EXPECT_NEAR(p.x1, q.x1, 0.01);
  EXPECT_NEAR(p.y0, q.y0, 0.01);
  EXPECT_NEAR(p.y1, q.y1, 0.01);
}

}  // namespace nonplanar::test
