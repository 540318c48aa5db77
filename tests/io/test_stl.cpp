#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "io/readers.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using test::unplaced;

TriangleMesh sample_solid() {
  return test::height_field_solid([](double x, double y) { return 5 + 0.1 * x + 0.05 * y * y; }, 0,
                                  10, 0, 8, 5, 4);
}

TEST(Stl, BinaryRoundTripKeepsGeometry) {
  const auto dir = test::temp_dir("stl_roundtrip");
  const TriangleMesh m = sample_solid();
  ASSERT_TRUE(write_stl(dir / "a.stl", m));
  auto r = load_mesh(dir / "a.stl", unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->format, MeshFormat::stl_binary);
  EXPECT_EQ(r->mesh.faces.size(), m.faces.size());
  EXPECT_EQ(r->mesh.vertices.size(), m.vertices.size());  // welded back to shared vertices
  EXPECT_NEAR(signed_volume(r->mesh), signed_volume(m), 1e-3);
  EXPECT_TRUE(r->defects.closed());
  EXPECT_EQ(r->defects.faces_flipped, 0u);
}

class StlLineEndings : public ::testing::TestWithParam<const char*> {};

TEST_P(StlLineEndings, AsciiParsesAndIgnoresStoredNormals) {
  const auto dir = test::temp_dir(std::string("stl_eol") + std::to_string(std::strlen(GetParam())) +
                                  (GetParam()[0] == '\r' ? "r" : "n"));
  const TriangleMesh m = sample_solid();
  test::write_bytes(dir / "a.stl", test::ascii_stl(m, GetParam()));
  auto r = load_mesh(dir / "a.stl", unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->format, MeshFormat::stl_ascii);
  EXPECT_EQ(r->mesh.faces.size(), m.faces.size());
  EXPECT_EQ(r->defects.faces_flipped, 0u);  // the (wrong) stored normals were not used
  EXPECT_NEAR(signed_volume(r->mesh), signed_volume(m), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Endings, StlLineEndings, ::testing::Values("\n", "\r\n", "\r"));

// Over the triangle limit: a clear error naming the file and both counts, not an attempt
// to build the mesh (the CLI's limit is 50 million).
TEST(Stl, MoreTrianglesThanTheLimitIsAnError) {
  const auto dir = test::temp_dir("stl_limit");
  ASSERT_TRUE(write_stl(dir / "box.stl", test::box({0, 0, 0}, {10, 10, 10})));
  LoadParams p;
  p.max_triangles = 11;
  const auto r = load_mesh(dir / "box.stl", p, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::invalid_mesh);
  EXPECT_NE(r.error().message.find("box.stl: 12 triangles, over the limit of 11"),
            std::string::npos)
      << r.error().message;
  p.max_triangles = 12;
  EXPECT_TRUE(load_mesh(dir / "box.stl", p, {}));
}

TEST(Stl, BinaryWhoseHeaderStartsWithSolidIsBinary) {
  const auto dir = test::temp_dir("stl_solid_header");
  const TriangleMesh m = sample_solid();
  ASSERT_TRUE(write_stl(dir / "a.stl", m));
  std::string bytes = test::read_bytes(dir / "a.stl");
  std::memcpy(bytes.data(), "solid trap", 10);
  test::write_bytes(dir / "a.stl", bytes);
  auto r = load_mesh(dir / "a.stl", unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->format, MeshFormat::stl_binary);
  EXPECT_EQ(r->mesh.faces.size(), m.faces.size());
}

TEST(Stl, SharedSpikeyTopNeedsToleranceWeld) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  const auto file = dir / "np_slic3r_nonplanar_spikey_top.stl";
  auto welded = load_mesh(file, {}, {});
  ASSERT_TRUE(welded) << welded.error().message;
  EXPECT_EQ(welded->format, MeshFormat::stl_binary);  // header starts with "solid "
  EXPECT_EQ(welded->mesh.faces.size(), 2730u);
  EXPECT_EQ(welded->defects.open_edges, 0u);
  LoadParams exact;
  exact.weld_tolerance_rel = 0;
  auto raw = load_mesh(file, exact, {});
  ASSERT_TRUE(raw);
  EXPECT_EQ(raw->defects.open_edges, 48u);  // the manifest's count for an exact weld
}

TEST(Stl, ZeroStoredNormalsAreIgnored) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto r = load_mesh(dir / "gen_cura_testModel.stl", {}, {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->defects.faces_flipped, 0u);
  EXPECT_GT(signed_volume(r->mesh), 5000.0);
}

// --- malformed input: one clear error, never a crash --------------------------------------

std::string binary_stl_bytes(const TriangleMesh& m) {
  const auto dir = test::temp_dir("stl_bytes");
  EXPECT_TRUE(write_stl(dir / "a.stl", m));
  return test::read_bytes(dir / "a.stl");
}

void expect_error(const std::string& bytes, Status status, const std::string& needle) {
  MeshFormat f;
  auto r = io::parse_stl(bytes, &f);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, status);
  EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
}

TEST(StlErrors, EmptyFile) {
  expect_error("", Status::parse_error, "empty");
}

TEST(StlErrors, TruncatedBinary) {
  std::string b = binary_stl_bytes(sample_solid());
  b.resize(b.size() - 7);
  expect_error(b, Status::parse_error, "truncated");
}

TEST(StlErrors, TriangleCountTwoToThe31) {
  std::string b = binary_stl_bytes(sample_solid());
  const std::uint32_t n = 1u << 31;
  std::memcpy(b.data() + 80, &n, 4);
  expect_error(b, Status::parse_error, "2147483648 triangles");
}

TEST(StlErrors, NanCoordinateInBinary) {
  std::string b = binary_stl_bytes(sample_solid());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(b.data() + 84 + 50 * 3 + 16, &nan, 4);
  expect_error(b, Status::parse_error, "triangle 4");
}

TEST(StlErrors, NonNumericAsciiNamesTheLine) {
  expect_error("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 blah 0\n",
               Status::parse_error, "line 5: vertex coordinate 'blah'");
}

TEST(StlErrors, InfinityIsRejected) {
  expect_error("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 inf\n", Status::parse_error,
               "line 4");
}

TEST(StlErrors, AsciiEndingInsideFacet) {
  expect_error("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n",
               Status::parse_error, "ends inside a facet");
}

TEST(StlErrors, ShortGarbage) {
  expect_error("hello", Status::parse_error, "too short");
}

TEST(StlErrors, LoaderPrefixesFileNameAndRejectsMissingFiles) {
  const auto dir = test::temp_dir("stl_missing");
  auto r = load_mesh(dir / "nope.stl", {}, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::io_error);
  EXPECT_EQ(r.error().message, (dir / "nope.stl").string() + ": file not found");
  auto d = load_mesh(dir, {}, {});
  ASSERT_FALSE(d);
  auto u = load_mesh(dir / "model.step", {}, {});
  ASSERT_FALSE(u);
  EXPECT_EQ(u.error().status, Status::unsupported);
}

TEST(StlErrors, AllFacesDegenerate) {
  const auto dir = test::temp_dir("stl_degenerate");
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {0, 0, 0}, {1, 1, 1}};
  m.faces = {{0, 1, 2}};
  ASSERT_TRUE(write_stl(dir / "a.stl", m));
  auto r = load_mesh(dir / "a.stl", {}, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::invalid_mesh);
}

}  // namespace
}  // namespace nonplanar
