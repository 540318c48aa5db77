// The 3MF package repair (io/zip_package.hpp): PrusaSlicer's `--export-3mf` names a thumbnail
// it does not write, and lib3mf refused the file ("Could not create OPC Part", #16).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "io/readers.hpp"
#include "io/zip_package.hpp"
#include "nonplanar/io.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

const char* kTetra =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" xmlns=\"http://"
    "schemas.microsoft.com/3dmanufacturing/core/2015/02\"><resources><object id=\"1\" "
    "type=\"model\"><mesh><vertices><vertex x=\"0\" y=\"0\" z=\"0\"/><vertex x=\"10\" y=\"0\" "
    "z=\"0\"/><vertex x=\"0\" y=\"10\" z=\"0\"/><vertex x=\"0\" y=\"0\" z=\"10\"/></vertices>"
    "<triangles><triangle v1=\"0\" v2=\"2\" v3=\"1\"/><triangle v1=\"0\" v2=\"1\" v3=\"3\"/>"
    "<triangle v1=\"1\" v2=\"2\" v3=\"3\"/><triangle v1=\"0\" v2=\"3\" v3=\"2\"/></triangles>"
    "</mesh></object></resources><build><item objectid=\"1\"/></build></model>";

// A one-tetrahedron 3MF with the given root relationships, as bytes.
std::string tetra_3mf(const std::string& name, const std::string& relationships) {
  const fs::path d = test::temp_dir(name);
  EXPECT_TRUE(test::zip_3mf(d, "p.3mf", relationships, kTetra));
  return test::read_bytes(d / "p.3mf");
}

const char* kThumbRel =
    "<Relationship Target=\"/Metadata/thumbnail.png\" Id=\"rel-2\" Type=\"http://schemas."
    "openxmlformats.org/package/2006/relationships/metadata/thumbnail\"/>";

TEST(ZipPackage, AThumbnailNamedButMissingIsDroppedAndTheModelLoads) {
  const std::string good = tetra_3mf("zip_good", test::kModelRelationship);
  EXPECT_FALSE(io::drop_dangling_relationships(good, nullptr));  // nothing to drop
  const std::string bad = tetra_3mf("zip_thumb", std::string(test::kModelRelationship) + kThumbRel);
  std::vector<std::string> dropped;
  const auto fixed = io::drop_dangling_relationships(bad, &dropped);
  ASSERT_TRUE(fixed);
  EXPECT_EQ(dropped, std::vector<std::string>{"/Metadata/thumbnail.png"});
  // The rebuilt package holds the same model: 4 faces, 10 mm tall.
  auto m = io::parse_3mf(*fixed);
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->faces.size(), 4u);
  auto direct = io::parse_3mf(bad);  // parse_3mf repairs by itself
  ASSERT_TRUE(direct) << direct.error().message;
  EXPECT_EQ(direct->faces.size(), 4u);
  EXPECT_FALSE(io::drop_dangling_relationships("PK\x05\x06 not really a zip", nullptr));
  // Found by fuzz_3mf: a local header offset of 0xffffffff wrapped a 32-bit "offset + 30"
  // past the bounds check and read outside the buffer.
  std::string hostile = bad;
  const std::size_t cd = hostile.find("PK\x01\x02");
  ASSERT_NE(cd, std::string::npos);
  hostile.replace(cd + 42, 4, "\xff\xff\xff\xff");
  EXPECT_FALSE(io::drop_dangling_relationships(hostile, nullptr));
}

// lib3mf writes ZIP64 packages (every size in an extra field, the directory's offset in a
// ZIP64 end record): a part of ours reads back from one, by name.
TEST(ZipPackage, PartsOfOurOwn3mfReadBack) {
  const fs::path d = test::temp_dir("zip_parts");
  const std::string plan(300000, 'x');
  ASSERT_TRUE(write_3mf(d / "p.3mf", test::box({0, 0, 0}, {20, 10, 5}),
                        {{"/Metadata/nonplanar_plan.json", plan}},
                        {"part", {{"layer_height", "0.2"}}, {}}));
  auto back = read_3mf_part(d / "p.3mf", "Metadata/nonplanar_plan.json");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(*back, plan);
  auto cfg = read_3mf_part(d / "p.3mf", "/Metadata/Slic3r_PE_model.config");
  ASSERT_TRUE(cfg);
  EXPECT_NE(cfg->find("key=\"layer_height\" value=\"0.2\""), std::string::npos) << *cfg;
  EXPECT_NE(cfg->find("key=\"name\" value=\"part\""), std::string::npos);
  auto missing = read_3mf_part(d / "p.3mf", "Metadata/other.json");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no Metadata/other.json in it"), std::string::npos);
  // The mesh still loads, named parts and all.
  auto m = load_mesh(d / "p.3mf", {}, {});
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->mesh.faces.size(), 12u);
}

TEST(ZipPackage, PrusaSlicersOwnExportLoads) {
  if (std::system("command -v prusa-slicer >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path d = test::temp_dir("zip_prusa");
  ASSERT_TRUE(write_stl(d / "box.stl", test::box({0, 0, 0}, {20, 10, 5})));
  const std::string cmd = "prusa-slicer --export-3mf -o '" + (d / "box.3mf").string() + "' '" +
                          (d / "box.stl").string() + "' >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  auto m = load_mesh(d / "box.3mf", {}, {});
  ASSERT_TRUE(m) << m.error().message;
  const BoundingBox b = bounding_box(m->mesh);
  EXPECT_NEAR(b.size().x(), 20, 1e-4);
  EXPECT_NEAR(b.size().y(), 10, 1e-4);
  EXPECT_NEAR(b.size().z(), 5, 1e-4);
}

}  // namespace
}  // namespace nonplanar
