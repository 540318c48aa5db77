// A plate saved by PrusaSlicer (#16: a 3MF's objects are sliced as separate objects where it
// places them). tests/data/prusaslicer_three_boxes.3mf is PrusaSlicer 2.5's
// `--export-3mf --duplicate 3` of one 15 x 10 x 4 mm box: three object instances, named only
// in its Metadata/Slic3r_PE_model.config.
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <sstream>

#include "support/cli.hpp"

namespace nonplanar {
namespace {

struct Extent {
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  int opened = 0;
};

// Each label's extrusions' XY extent, from "; printing object NAME" to "; stop printing".
std::map<std::string, Extent> labelled(const std::string& gcode, std::size_t* outside) {
  std::map<std::string, Extent> out;
  std::istringstream in(gcode);
  std::string now;
  *outside = 0;
  for (std::string s; std::getline(in, s);) {
    if (s.rfind("; printing object ", 0) == 0) now = s.substr(18), ++out[now].opened;
    if (s.rfind("; stop printing object ", 0) == 0) now.clear();
    if (s.rfind("G1 ", 0) != 0 || s.find(" E") == std::string::npos) continue;
    const std::size_t x = s.find(" X"), y = s.find(" Y");
    if (x == std::string::npos || y == std::string::npos) continue;
    if (now.empty()) {
      ++*outside;
      continue;
    }
    Extent& e = out[now];
    const double px = std::atof(s.c_str() + x + 2), py = std::atof(s.c_str() + y + 2);
    e.x0 = std::min(e.x0, px), e.x1 = std::max(e.x1, px);
    e.y0 = std::min(e.y0, py), e.y1 = std::max(e.y1, py);
  }
  return out;
}

TEST(PlateCli, PrusaSlicersPlateOfThreeBoxesPrintsThreeLabelledObjects) {
  const auto dir = test::temp_dir("plate_cli");
  const std::string model = std::string(NONPLANAR_TEST_DATA) + "/prusaslicer_three_boxes.3mf";
  const auto r = test::run_cli("slice '" + model + "' --skirts 0 --set gcode_label_objects=1 -o '" +
                               (dir / "plate.gcode").string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  std::size_t outside = 0;
  const auto got = labelled(test::read_bytes(dir / "plate.gcode"), &outside);
  EXPECT_EQ(outside, 0u);  // every extrusion with X and Y (the purge line has no X) is labelled
  ASSERT_EQ(got.size(), 3u);
  // PrusaSlicer's own labels for the three instances, each opened once in each of 20 layers,
  // round the place the 3MF gives it (the plate is centred on the bed as a whole: its items
  // at x 82-118, y 87-113 move by (+10, +10)).
  const std::map<std::string, std::pair<double, double>> centre = {
      {"box.stl id:0 copy 0", {120.5, 102}},
      {"box.stl id:0 copy 1", {120.5, 118}},
      {"box.stl id:0 copy 2", {99.5, 110}}};
  for (const auto& [name, c] : centre) {
    SCOPED_TRACE(name);
    ASSERT_EQ(got.count(name), 1u);
    const Extent& e = got.at(name);
    EXPECT_EQ(e.opened, 20);
    EXPECT_NEAR(0.5 * (e.x0 + e.x1), c.first, 0.05);
    EXPECT_NEAR(0.5 * (e.y0 + e.y1), c.second, 0.05);
    EXPECT_LT(e.x1 - e.x0, 15);
    EXPECT_LT(e.y1 - e.y0, 10);
  }
}

}  // namespace
}  // namespace nonplanar
