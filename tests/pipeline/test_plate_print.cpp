// A plate of two objects through the whole pipeline (#16: a 3MF's objects are sliced as
// separate objects where it places them): each layer prints one object after the other, each
// inside its own cancel label, and the curved one keeps its curved top.
#include <gtest/gtest.h>

#include <sstream>

#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

TEST(PlatePrint, EachObjectPrintsInsideItsOwnLabelAndTheDomeStaysCurved) {
  PrintConfig c;
  ASSERT_TRUE(set_config_value(c, "gcode_label_objects", "firmware"));
  c.gcode.objects = {{"dome", 0, 0}, {"block", 1, 0}};
  TriangleMesh plate = test::dome_cut_by_box();  // 24 x 24 mm round (0, 0), 6-9.5 mm tall
  PlateObjects objects;
  objects.items = c.gcode.objects;
  objects.face.assign(plate.faces.size(), 0);
  test::append(plate, test::box({20, -6, 0}, {32, 6, 6}));
  objects.face.resize(plate.faces.size(), 1);
  plate = test::placed(plate, c);
  SliceJob job = make_job(c);
  job.objects = object_outlines(plate, objects);
  ASSERT_EQ(job.objects.size(), 2u);
  auto r = slice_model(plate, job, {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_TRUE(r->nonplanar);
  EXPECT_EQ(r->plan.stacks.size(), 1u);
  EXPECT_EQ(r->collisions, 0u);

  // Which label each line is in, then every extrusion of the part against its label's box.
  std::istringstream in(r->gcode);
  std::vector<int> label{-1};  // label[line], 1-based lines
  int now = -1, opened[2] = {0, 0};
  for (std::string s; std::getline(in, s);) {
    if (s.rfind("M486 S", 0) == 0) {
      now = std::stoi(s.substr(6));
      if (now >= 0 && now < 2) ++opened[now];
    }
    label.push_back(now);
  }
  EXPECT_EQ(now, -1);
  EXPECT_NE(r->gcode.find("M486 T2\n"), std::string::npos);
  auto moves = read_gcode_moves(r->gcode);
  ASSERT_TRUE(moves) << moves.error().message;
  std::size_t checked[2] = {0, 0}, stray = 0;
  for (const PrintMove& m : *moves) {
    if (!m.extruding || m.type == "Skirt/Brim" || m.type == "Custom") continue;
    const int k = label[static_cast<std::size_t>(m.line)];
    if (k < 0 || k > 1) {
      ++stray;
      continue;
    }
    BoundingBox b = job.objects[static_cast<std::size_t>(k)].box;
    b.min -= Vec3(0.5, 0.5, 0.5), b.max += Vec3(0.5, 0.5, 0.5);
    EXPECT_TRUE(b.contains(m.to)) << "line " << m.line << " in object " << k;
    ++checked[k];
  }
  EXPECT_EQ(stray, 0u);
  EXPECT_GT(checked[0], 1000u);
  EXPECT_GT(checked[1], 1000u);
  // The block is 6 mm of 0.2 mm layers: its label opens once in each, and so does the dome's.
  EXPECT_EQ(opened[1], 30);
  EXPECT_EQ(opened[0], static_cast<int>(r->layers.size()));
}

}  // namespace
}  // namespace nonplanar
