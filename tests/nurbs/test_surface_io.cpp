#include <gtest/gtest.h>

#include <sstream>

#include "nonplanar/patch_fit.hpp"
#include "nonplanar/surface_io.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

SurfaceRecord sample_record() {
  const TriangleMesh m = test::height_field_solid(
      [](double x, double y) { return 5 + 0.3 * std::sin(x / 3) + 0.01 * y * y; }, 0, 20, 0, 10, 40,
      20);
  auto a = analyze(m, {}, {});
  EXPECT_TRUE(a);
  auto f = fit_patch(m, a->patches.front(), {}, {});
  EXPECT_TRUE(f);
  return {0, f->surface, f->rms_error, f->max_error};
}

TEST(SurfaceIo, JsonRoundTripEvaluatesIdentically) {
  const auto dir = test::temp_dir("surface_json");
  const SurfaceRecord r = sample_record();
  ASSERT_TRUE(write_surfaces_json(dir / "s.json", {r, r}));
  auto back = read_surfaces_json(dir / "s.json");
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->size(), 2u);
  const HeightField& h = (*back)[1].surface;
  for (double x = 0; x <= 20; x += 0.7)
    for (double y = 0; y <= 10; y += 0.9) EXPECT_NEAR(h.height(x, y), r.surface.height(x, y), 1e-9);
  EXPECT_DOUBLE_EQ((*back)[0].rms_error, r.rms_error);
}

TEST(SurfaceIo, RejectsMalformedDocuments) {
  EXPECT_FALSE(parse_surfaces_json("{"));
  EXPECT_FALSE(parse_surfaces_json("{\"format\": \"something else\"}"));
  EXPECT_FALSE(parse_surfaces_json("{\"format\": \"nonplanar-surfaces\", \"version\": 1}"));
  // Knot count inconsistent with the control grid.
  auto bad = parse_surfaces_json(
      R"({"format":"nonplanar-surfaces","version":1,"surfaces":[{"patch":0,"degree_u":1,
      "degree_v":1,"count_u":2,"count_v":2,"knots_u":[0,0,1],"knots_v":[0,0,1,1],
      "control_points":[[0,0,0],[0,1,0],[1,0,0],[1,1,0]],"weights":[1,1,1,1],
      "uv_map":{"origin":[0,0],"extent":[1,1]}}]})");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("surface 0"), std::string::npos);
  auto type = parse_surfaces_json(
      R"({"format":"nonplanar-surfaces","version":1,"surfaces":[{"patch":"x"}]})");
  ASSERT_FALSE(type);
  // Wrong types in the header are errors, not exceptions (fuzz_surfaces found the first).
  const auto num = parse_surfaces_json(R"({"format":1111188888888888000000000000110})");
  ASSERT_FALSE(num);
  EXPECT_EQ(num.error().status, Status::parse_error);
  const auto ver = parse_surfaces_json(R"({"format":"nonplanar-surfaces","version":"1"})");
  ASSERT_FALSE(ver);
  EXPECT_EQ(ver.error().status, Status::unsupported);
  EXPECT_FALSE(parse_surfaces_json(R"([{"format":"nonplanar-surfaces"}])"));
  // A float or a huge number where an integer belongs is an error naming the key, not a cast
  // (UBSan caught fuzz_surfaces casting 2.2e101 to int).
  const std::pair<const char*, const char*> cases[] = {
      {R"("patch":2.22222e101)", "patch"},
      {R"("patch":1.5)", "patch"},
      {R"("patch":4294967296)", "patch"},
      {R"("patch":0,"degree_u":-9223372036854775808)", "degree_u"}};
  for (const auto& [field, key] : cases) {
    const auto r = parse_surfaces_json(
        std::string(R"({"format":"nonplanar-surfaces","version":1,"surfaces":[{)") + field + "}]}");
    ASSERT_FALSE(r) << field;
    EXPECT_EQ(r.error().status, Status::parse_error);
    EXPECT_NE(r.error().message.find(key), std::string::npos) << r.error().message;
  }
}

TEST(SurfaceIo, ObjTessellationHasOneGridPerSurface) {
  const auto dir = test::temp_dir("surface_obj");
  const SurfaceRecord r = sample_record();
  ASSERT_TRUE(write_surfaces_obj(dir / "s.obj", {r}, 8));
  const std::string text = test::read_bytes(dir / "s.obj");
  std::size_t vertices = 0, faces = 0;
  std::istringstream lines(text);
  for (std::string l; std::getline(lines, l);) {
    vertices += l.rfind("v ", 0) == 0;
    faces += l.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(vertices, 81u);  // 9 × 9 grid points
  EXPECT_EQ(faces, 128u);    // 8 × 8 quads, two triangles each
  EXPECT_NE(text.find("g patch_0"), std::string::npos);
}

}  // namespace
}  // namespace nonplanar
