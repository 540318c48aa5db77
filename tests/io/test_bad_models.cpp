// Every bad_* model in ../shared/models, with the exact outcome the loader must give.
// Counts are of the welded mesh (tolerance 1e-6 of the diagonal): faces whose corners weld
// together are dropped ("collapsed"), which is why some manifest counts (taken on the raw
// file) are higher. Zero-area means height below the weld tolerance.
#include <gtest/gtest.h>

#include "nonplanar/analysis.hpp"
#include "nonplanar/io.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

struct Expect {
  const char* file;
  std::size_t faces, open, non_manifold, inconsistent, zero_area, collapsed, dup, shells, flipped;
  bool inverted;
};

const Expect kExpect[] = {
    // file                                     faces open nm  inc   zero coll dup shells flip inv
    {"bad_aaron_mouse_nonmanifold.stl", 256, 0, 0, 0, 0, 4, 0, 1, 0, false},
    {"bad_assimp_Spider_binary.stl", 1312, 72, 0, 10, 0, 56, 0, 18, 4, false},
    {"bad_assimp_sphereWithHole.stl", 285, 9, 0, 0, 0, 0, 0, 1, 0, false},
    {"bad_cgal_blobby-shuffled.off", 4050, 0, 0, 3069, 0, 0, 0, 1, 2017, false},
    {"bad_cgal_elephant-with-holes.off", 4463, 1353, 0, 0, 0, 0, 0, 1, 0, false},
    {"bad_cgal_ellipsoid_inverted.off", 3108, 0, 0, 0, 0, 0, 0, 1, 3108, true},
    {"bad_manifold_openscad-nonmanifold-crash.obj", 1435, 0, 19, 0, 34, 6, 1, 1, 0, false},
    {"bad_manifold_self_intersectA.obj", 17160, 0, 0, 0, 0, 0, 0, 1, 0, false},
    {"bad_openscad_back-to-back.stl", 10, 0, 2, 0, 2, 0, 0, 1, 0, false},
    {"bad_openscad_bad-stl-wing.stl", 842, 0, 0, 0, 24, 0, 0, 1, 0, false},
    {"bad_openscad_zero-area-triangle.stl", 14, 0, 0, 0, 1, 0, 0, 1, 0, false},
};

// Readable test names in ctest output instead of the struct's bytes.
void PrintTo(const Expect& e, std::ostream* os) {
  *os << e.file;
}

class BadModel : public ::testing::TestWithParam<Expect> {};

TEST_P(BadModel, LoadsWithExactDefectsAndAnalyses) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  const Expect& e = GetParam();
  auto r = load_mesh(dir / e.file, {}, {});
  ASSERT_TRUE(r) << r.error().message;
  const MeshDefects& d = r->defects;
  EXPECT_EQ(r->mesh.faces.size(), e.faces);
  EXPECT_EQ(d.open_edges, e.open);
  EXPECT_EQ(d.non_manifold_edges, e.non_manifold);
  EXPECT_EQ(d.inconsistent_edges, e.inconsistent);
  EXPECT_EQ(d.zero_area_faces, e.zero_area);
  EXPECT_EQ(d.collapsed_faces, e.collapsed);
  EXPECT_EQ(d.duplicate_faces, e.dup);
  EXPECT_EQ(d.shells, e.shells);
  EXPECT_EQ(d.faces_flipped, e.flipped);
  EXPECT_EQ(d.was_inverted, e.inverted);
  EXPECT_GT(signed_volume(r->mesh), 0.0);  // every one ends up pointing outward
  EXPECT_EQ(r->warnings.empty(), !d.any());
  auto a = analyze(r->mesh, {}, {});
  ASSERT_TRUE(a) << a.error().message;
}

INSTANTIATE_TEST_SUITE_P(Shared, BadModel, ::testing::ValuesIn(kExpect),
                         [](const auto& param_info) {
                           std::string n = param_info.param.file;
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

TEST(BadModel, InvalidVertexIsAParseErrorNamingTheLine) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto r = load_mesh(dir / "bad_openscad_invalidvertex.stl", {}, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::parse_error);
  EXPECT_EQ(r.error().message, (dir / "bad_openscad_invalidvertex.stl").string() +
                                   ": line 89: vertex coordinate 'blah' is not a finite number");
}

}  // namespace
}  // namespace nonplanar
