#include <gtest/gtest.h>

#include <cmath>

#include "io/readers.hpp"
#include "nonplanar/io.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A unit cube as 6 quads, using every OBJ index form.
const char* kCubeObj =
    "# cube\nmtllib x.mtl\no cube\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1 1.0\n"
    "vt 0 0\nvn 0 0 1\ns off\n"
    "f 1 4 3 2\n"                  // bottom
    "f 5/1 6/1 7/1 8/1\n"          // top
    "f 1//1 2//1 6//1 5//1\n"      // front
    "f 2/1/1 3/1/1 7/1/1 6/1/1\n"  // right
    "f -6 -5 -1 -2\n"              // back: 3 4 8 7 counted from the end
    "f 4 1 5 8\n";                 // left

TEST(Obj, QuadsAndIndexFormsMakeAClosedCube) {
  auto r = io::parse_obj(kCubeObj);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->faces.size(), 12u);
  EXPECT_NEAR(signed_volume(*r), 1.0, 1e-12);
}

TEST(Obj, LoaderWeldsAndPlaces) {
  const auto dir = test::temp_dir("obj_load");
  test::write_bytes(dir / "cube.OBJ", kCubeObj);
  LoadParams p;
  p.scale = 10;
  auto r = load_mesh(dir / "cube.OBJ", p, {});
  ASSERT_TRUE(r) << r.error().message;
  const BoundingBox b = bounding_box(r->mesh);
  EXPECT_NEAR(b.min.z(), 0.0, 1e-12);
  EXPECT_NEAR(0.5 * (b.min.x() + b.max.x()), 110.0, 1e-9);
  EXPECT_NEAR(0.5 * (b.min.y() + b.max.y()), 110.0, 1e-9);
  EXPECT_NEAR(signed_volume(r->mesh), 1000.0, 1e-9);
  EXPECT_TRUE(r->defects.closed());
}

TEST(ObjErrors, IndexOutOfRangeNamesTheLine) {
  auto r = io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "line 5: face index 9 is out of range (3 vertices)");
  auto z = io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  ASSERT_FALSE(z);
  EXPECT_NE(z.error().message.find("line 4"), std::string::npos);
  auto neg = io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  ASSERT_FALSE(neg);
  EXPECT_NE(neg.error().message.find("out of range"), std::string::npos);
}

TEST(ObjErrors, BadNumbersAndEmptyMeshes) {
  EXPECT_FALSE(io::parse_obj("v 0 0 nan\n"));
  EXPECT_FALSE(io::parse_obj("v 0 0\nv 1 1 1\n"));  // coordinate missing on its line
  EXPECT_FALSE(io::parse_obj("v 0 0 0\nf 1 1\n"));
  auto none = io::parse_obj("v 0 0 0\nv 1 0 0\n");
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().status, Status::invalid_mesh);
  EXPECT_FALSE(io::parse_obj(""));
}

const char* kTetraOff =
    "OFF # a tetrahedron\n"
    "# counts\n4 4 6\n"
    "0 0 0\n1 0 0\n0 1 0\n0 0 1   # apex\n"
    "3 0 2 1 255 0 0\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";

TEST(Off, ParsesCommentsAndFaceColours) {
  auto r = io::parse_off(kTetraOff);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->faces.size(), 4u);
  EXPECT_NEAR(signed_volume(*r), 1.0 / 6.0, 1e-12);
}

TEST(Off, CountsOnHeaderLineAndPolygons) {
  auto r = io::parse_off(
      "OFF 8 6 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
      "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->faces.size(), 12u);
  EXPECT_NEAR(signed_volume(*r), 1.0, 1e-12);
}

TEST(OffErrors, TruncatedLyingAndOutOfRange) {
  auto t = io::parse_off("OFF\n4 4 6\n0 0 0\n1 0 0\n");
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("after 2 of 4 vertices"), std::string::npos);
  auto huge = io::parse_off("OFF\n2000000000 1 0\n0 0 0\n");
  ASSERT_FALSE(huge);
  EXPECT_NE(huge.error().message.find("exceed"), std::string::npos);
  auto oor = io::parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  ASSERT_FALSE(oor);
  EXPECT_NE(oor.error().message.find("line 6"), std::string::npos);
  EXPECT_FALSE(io::parse_off("PLY\n"));
  EXPECT_FALSE(io::parse_off("OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_FALSE(io::parse_off("OFF\n-3 1 0\n"));
}

// The vertices and triangles of amf_text's object, read back (indices from 0).
TriangleMesh read_amf_text(const std::string& text) {
  TriangleMesh m;
  auto values = [&](const char* open, const char* close) {
    std::vector<double> out;
    const std::string o = open, c = close;
    for (std::size_t at = text.find(o); at != std::string::npos; at = text.find(o, at + 1)) {
      const std::size_t from = at + o.size();
      out.push_back(std::stod(text.substr(from, text.find(c, from) - from)));
    }
    return out;
  };
  const auto x = values("<x>", "</x>"), y = values("<y>", "</y>"), z = values("<z>", "</z>");
  const auto a = values("<v1>", "</v1>"), b = values("<v2>", "</v2>"), c = values("<v3>", "</v3>");
  for (std::size_t i = 0; i < x.size(); ++i) m.vertices.emplace_back(x[i], y[i], z[i]);
  for (std::size_t i = 0; i < a.size(); ++i)
    m.faces.push_back({static_cast<int>(a[i]), static_cast<int>(b[i]), static_cast<int>(c[i])});
  return m;
}

// amf_text is what PrusaSlicer reads through a pipe instead of our STL (external_engine.cpp):
// it must give the same floats, vertex for vertex, as the binary STL of the mesh.
TEST(AmfText, ReadsBackAsTheBinaryStlOfTheMesh) {
  TriangleMesh m = test::icosphere(Vec3(110.3, 97.1, 12.0), 11.7, 3);
  for (Vec3& v : m.vertices) v.z() += 0.013 * std::sin(0.37 * v.x()) + 1e-7 / 3;  // off float
  std::size_t collapsed = 7;
  const std::string text = amf_text(m, &collapsed, {{"slic3r.layer_height_profile", "0;0.2"}});
  EXPECT_EQ(collapsed, 0u);
  EXPECT_EQ(text.rfind("<?xml", 0), 0u);
  EXPECT_NE(text.find("<metadata type=\"slic3r.layer_height_profile\">0;0.2</metadata>"),
            std::string::npos);
  const TriangleMesh back = read_amf_text(text);
  const auto dir = test::temp_dir("amf_text");
  ASSERT_TRUE(write_stl(dir / "m.stl", m));
  MeshFormat format{};
  auto stl = io::parse_stl(test::read_bytes(dir / "m.stl"), &format);
  ASSERT_TRUE(stl) << stl.error().message;
  ASSERT_EQ(back.faces.size(), m.faces.size());
  ASSERT_EQ(back.vertices.size(), m.vertices.size());  // shared as the mesh shares them
  ASSERT_EQ(stl->faces.size(), m.faces.size());
  for (std::size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = back.vertices[static_cast<std::size_t>(back.faces[f][k])];
      const Vec3& b = stl->vertices[stl->faces[f][k]];
      for (int d = 0; d < 3; ++d) {
        ASSERT_EQ(a[d], b[d]) << "face " << f << " corner " << k;
        ASSERT_EQ(a[d], static_cast<double>(static_cast<float>(m.vertices[m.faces[f][k]][d])));
      }
    }
}

// A support blocker is a volume of its own after the part's, its type in metadata before its
// triangles (PrusaSlicer's AMF reader), its vertices among the object's.
TEST(AmfText, ASupportBlockerIsAVolumeOfItsOwn) {
  const TriangleMesh part = test::box({0, 0, 0}, {10, 10, 5});
  const TriangleMesh blocker = test::box({-1, -1, 3}, {11, 11, 6});
  std::size_t collapsed = 9;
  const std::string text = amf_text(part, &collapsed, {}, {blocker});
  EXPECT_EQ(collapsed, 0u);
  const std::size_t second = text.find("<volume>", text.find("<volume>") + 1);
  ASSERT_NE(second, std::string::npos);
  EXPECT_EQ(text.find("<volume>", second + 1), std::string::npos);
  EXPECT_EQ(text.find("<metadata type=\"slic3r.volume_type\">SupportBlocker</metadata>"),
            second + 9);
  const TriangleMesh back = read_amf_text(text);
  EXPECT_EQ(back.faces.size(), part.faces.size() + blocker.faces.size());
  EXPECT_EQ(back.vertices.size(), 16u);  // no corner shared
  for (std::size_t f = part.faces.size(); f < back.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec3& v = back.vertices[static_cast<std::size_t>(back.faces[f][k])];
      EXPECT_TRUE(v.z() == 3 || v.z() == 6);
    }
}

TEST(AmfText, FacesThatCollapseInFloatAreLeftOutAndCounted) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10 + 1e-7, 0, 0}};  // 1 and 3: one float
  m.faces = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}};
  std::size_t collapsed = 0;
  const TriangleMesh back = read_amf_text(amf_text(m, &collapsed));
  EXPECT_EQ(collapsed, 1u);
  EXPECT_EQ(back.faces.size(), 2u);
  EXPECT_EQ(back.vertices.size(), 3u);  // 1 and 3 shared, as an STL reader shares them
}

}  // namespace
}  // namespace nonplanar
