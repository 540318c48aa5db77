// A plate of several objects: whose a path is, and each layer printed object by object.
#include <gtest/gtest.h>

#include <algorithm>

#include "nonplanar/program.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// Object 0: an L (two boxes) whose box holds all of object 1, a block in the L's crook.
struct Plate {
  TriangleMesh mesh;
  PlateObjects objects;
  void add(const TriangleMesh& m, int object) {
    test::append(mesh, m);
    objects.face.resize(mesh.faces.size(), object);
  }
};

Plate l_and_block() {
  Plate p;
  p.objects.items = {{"L", 0, 0}, {"block", 1, 0}};
  p.add(test::box({0, 0, 0}, {30, 6, 4}), 0);
  p.add(test::box({0, 6, 0}, {6, 30, 4}), 0);
  p.add(test::box({12, 12, 0}, {28, 28, 9}), 1);
  return p;
}

TEST(PlateObjects, TheFootprintTellsWhoseAPointIsWhereBoxesOverlap) {
  const Plate p = l_and_block();
  const std::vector<ObjectOutline> o = object_outlines(p.mesh, p.objects);
  ASSERT_EQ(o.size(), 2u);
  // The L's shadow: 30·6 + 6·24 mm², and half a cell's diagonal round it at most.
  ASSERT_FALSE(o[0].shadow.empty());
  const double cell2 = o[0].cell * o[0].cell;
  const double a =
      cell2 * static_cast<double>(std::count(o[0].shadow.begin(), o[0].shadow.end(), 1));
  EXPECT_GE(a, 30 * 6 + 6 * 24);
  EXPECT_LE(a, 30 * 6 + 6 * 24 + (2 * 30 + 2 * 30) * 2 * o[0].cell);
  EXPECT_FALSE(o[0].covers(Vec2(15, 15)));
  EXPECT_TRUE(o[0].covers(Vec2(5.9, 15)));
  EXPECT_NEAR(o[1].box.max.z(), 9, 1e-9);
  EXPECT_EQ(object_at(o, Vec3(20, 20, 1)), 1);  // in both boxes, in the block's shadow
  EXPECT_EQ(object_at(o, Vec3(3, 20, 1)), 0);   // in both boxes, on the L's arm
  EXPECT_EQ(object_at(o, Vec3(20, 3, 1)), 0);
  EXPECT_EQ(object_at(o, Vec3(20, 20, 8)), 1);  // above the L's top
  // One object: no outlines, and every point is object 0.
  PlateObjects one;
  EXPECT_TRUE(object_outlines(p.mesh, one).empty());
  EXPECT_EQ(object_at({}, Vec3(20, 20, 1)), 0);
}

TEST(PlateObjects, EachLayerPrintsObjectByObjectInItsOwnOrder) {
  const Plate p = l_and_block();
  const std::vector<ObjectOutline> o = object_outlines(p.mesh, p.objects);
  auto path = [](ExtrusionRole role, double x, double y, int tag) {
    ExtrusionPath e;
    e.role = role;
    e.points = {Vec3(x, y, 0.2), Vec3(x + 0.5, y, 0.2), Vec3(x + 1, y, 0.2)};
    e.height.assign(3, 0.2);
    e.width = 0.4 + 0.01 * tag;  // which path it was
    return e;
  };
  std::vector<LayerToolpaths> layers(1);
  layers[0].paths = {path(ExtrusionRole::perimeter, 15, 15, 0),  // block
                     path(ExtrusionRole::skirt, -5, -5, 1),
                     path(ExtrusionRole::perimeter, 2, 20, 2),         // L
                     path(ExtrusionRole::internal_infill, 20, 20, 3),  // block
                     path(ExtrusionRole::internal_infill, 20, 2, 4)};  // L
  group_by_object(layers, o);
  std::vector<int> order, object;
  for (const ExtrusionPath& e : layers[0].paths) {
    order.push_back(static_cast<int>(std::lround((e.width - 0.4) * 100)));
    object.push_back(e.object);
  }
  EXPECT_EQ(order, (std::vector<int>{1, 2, 4, 0, 3}));
  EXPECT_EQ(object, (std::vector<int>{0, 0, 0, 1, 1}));
  // Fewer than two outlines: nothing moves.
  std::vector<LayerToolpaths> same = layers;
  std::swap(same[0].paths[1], same[0].paths[4]);
  const std::vector<LayerToolpaths> before = same;
  group_by_object(same, {o[0]});
  for (std::size_t i = 0; i < before[0].paths.size(); ++i)
    EXPECT_EQ(same[0].paths[i].width, before[0].paths[i].width);
}

}  // namespace
}  // namespace nonplanar
