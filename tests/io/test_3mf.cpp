#include <Model/COM/NMR_DLLInterfaces.h>
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <string>

#include "io/readers.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A cube mesh object in a fresh lib3mf model (released by the caller with the model).
NMR::PLib3MFModelMeshObject* add_cube(NMR::PLib3MFModel* model) {
  const TriangleMesh cube = test::box({0, 0, 0}, {1, 1, 1});
  NMR::PLib3MFModelMeshObject* obj = nullptr;
  EXPECT_EQ(NMR::lib3mf_model_addmeshobject(model, &obj), 0);
  std::vector<NMR::MODELMESHVERTEX> v(cube.vertices.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) v[i].m_fPosition[k] = static_cast<float>(cube.vertices[i][k]);
  std::vector<NMR::MODELMESHTRIANGLE> t(cube.faces.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    for (int k = 0; k < 3; ++k) t[i].m_nIndices[k] = static_cast<DWORD>(cube.faces[i][k]);
  EXPECT_EQ(NMR::lib3mf_meshobject_setgeometry(obj, v.data(), static_cast<DWORD>(v.size()),
                                               t.data(), static_cast<DWORD>(t.size())),
            0);
  return obj;
}

std::string write_model(NMR::PLib3MFModel* model, const std::filesystem::path& file) {
  NMR::PLib3MFModelWriter* writer = nullptr;
  EXPECT_EQ(NMR::lib3mf_model_querywriter(model, "3mf", &writer), 0);
  EXPECT_EQ(NMR::lib3mf_writer_writetofileutf8(writer, file.c_str()), 0);
  NMR::lib3mf_release(writer);
  return test::read_bytes(file);
}

NMR::MODELTRANSFORM identity() {
  NMR::MODELTRANSFORM m{};
  for (int k = 0; k < 3; ++k) m.m_fFields[k][k] = 1;
  return m;
}

TEST(ThreeMf, RoundTrip) {
  const auto dir = test::temp_dir("3mf_roundtrip");
  const TriangleMesh m =
      test::height_field_solid([](double x, double) { return 4 + 0.2 * x; }, 0, 10, 0, 5, 4, 3);
  ASSERT_TRUE(write_3mf(dir / "a.3mf", m));
  auto r = load_mesh(dir / "a.3mf", test::unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->format, MeshFormat::threemf);
  EXPECT_EQ(r->mesh.faces.size(), m.faces.size());
  EXPECT_NEAR(signed_volume(r->mesh), signed_volume(m), 1e-4);
  EXPECT_TRUE(r->defects.closed());
}

// A support blocker is a volume of the object, after the part's faces, that the slicer does
// not print: PrusaSlicer's config marks it, and our reader leaves it (faces and vertices) out.
TEST(ThreeMf, ASupportBlockerIsNoPartOfTheMesh) {
  const auto dir = test::temp_dir("3mf_blocker");
  const TriangleMesh part =
      test::height_field_solid([](double x, double) { return 4 + 0.2 * x; }, 0, 10, 0, 5, 4, 3);
  Object3mf o{"ramp", {{"layer_height", "0.2"}}, {test::box({-1, -1, 5}, {11, 6, 8})}};
  ASSERT_TRUE(write_3mf(dir / "b.3mf", part, {}, o));
  auto cfg = read_3mf_part(dir / "b.3mf", "Metadata/Slic3r_PE_model.config");
  ASSERT_TRUE(cfg) << cfg.error().message;
  const std::string last = std::to_string(part.faces.size() - 1);
  EXPECT_NE(cfg->find("<volume firstid=\"0\" lastid=\"" + last + "\">"), std::string::npos) << *cfg;
  EXPECT_NE(cfg->find("<volume firstid=\"" + std::to_string(part.faces.size()) + "\" lastid=\"" +
                      std::to_string(part.faces.size() + 11) + "\">"),
            std::string::npos)
      << *cfg;
  EXPECT_NE(cfg->find("key=\"volume_type\" value=\"SupportBlocker\""), std::string::npos);
  auto r = load_mesh(dir / "b.3mf", test::unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->mesh.faces.size(), part.faces.size());
  EXPECT_NEAR(signed_volume(r->mesh), signed_volume(part), 1e-4);
  const BoundingBox box = bounding_box(r->mesh);
  EXPECT_NEAR(box.max.z(), 6.0, 1e-4);  // the blocker's 8 mm and -1 mm are gone
  EXPECT_NEAR(box.min.x(), 0.0, 1e-4);
  EXPECT_TRUE(r->defects.closed());
  EXPECT_FALSE(r->objects.several());
}

// Two build items of one object, each with its own transform: both must come in, moved.
TEST(ThreeMf, BuildItemsAndTransformsAreApplied) {
  const auto dir = test::temp_dir("3mf_transform");
  NMR::PLib3MFModel* model = nullptr;
  ASSERT_EQ(NMR::lib3mf_createmodel(&model), 0);
  NMR::PLib3MFModelMeshObject* obj = add_cube(model);
  NMR::MODELTRANSFORM a = identity(), b = identity();
  a.m_fFields[0][3] = 10;  // translate x by 10
  b.m_fFields[0][0] = 2;   // scale x by 2, then move z by 5
  b.m_fFields[2][3] = 5;
  NMR::PLib3MFModelBuildItem *ia = nullptr, *ib = nullptr;
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, obj, &a, &ia), 0);
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, obj, &b, &ib), 0);
  write_model(model, dir / "two.3mf");
  for (auto* p : {static_cast<NMR::PLib3MFBase*>(ia), ib, obj, model}) NMR::lib3mf_release(p);

  auto r = load_mesh(dir / "two.3mf", test::unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->mesh.faces.size(), 24u);
  EXPECT_EQ(r->defects.shells, 2u);
  EXPECT_NEAR(signed_volume(r->mesh), 1.0 + 2.0, 1e-6);
  const BoundingBox box = bounding_box(r->mesh);
  EXPECT_NEAR(box.min.x(), 0.0, 1e-6);
  EXPECT_NEAR(box.max.x(), 11.0, 1e-6);
  EXPECT_NEAR(box.max.z(), 6.0, 1e-6);
}

// #16: a plate's objects stay apart. Each build item is an object with its object's name
// ("object K" without one), and each face knows its object through welding.
TEST(ThreeMf, SeveralObjectsKeepTheirNamesAndFaces) {
  const auto dir = test::temp_dir("3mf_objects");
  NMR::PLib3MFModel* model = nullptr;
  ASSERT_EQ(NMR::lib3mf_createmodel(&model), 0);
  NMR::PLib3MFModelMeshObject* a = add_cube(model);
  NMR::PLib3MFModelMeshObject* b = add_cube(model);
  ASSERT_EQ(NMR::lib3mf_object_setnameutf8(a, "left cube"), 0);
  NMR::MODELTRANSFORM at = identity(), bt = identity(), ct = identity();
  bt.m_fFields[0][3] = 10, ct.m_fFields[1][3] = 10;
  NMR::PLib3MFModelBuildItem *ia = nullptr, *ib = nullptr, *ic = nullptr;
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, a, &at, &ia), 0);
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, b, &bt, &ib), 0);
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, a, &ct, &ic), 0);  // a second instance
  write_model(model, dir / "plate.3mf");
  for (auto* p : {static_cast<NMR::PLib3MFBase*>(ia), ib, ic, a, b, model}) NMR::lib3mf_release(p);

  auto r = load_mesh(dir / "plate.3mf", test::unplaced(), {});
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->objects.items.size(), 3u);
  const std::vector<std::string> names = {"left cube", "object 2", "left cube"};
  const std::vector<int> ids = {0, 1, 0}, copies = {0, 0, 1};  // the third: cube a again
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(r->objects.items[k].name, names[k]);
    EXPECT_EQ(r->objects.items[k].id, ids[k]);
    EXPECT_EQ(r->objects.items[k].copy, copies[k]);
  }
  ASSERT_EQ(r->objects.face.size(), r->mesh.faces.size());
  std::array<int, 3> faces{};
  for (std::size_t f = 0; f < r->mesh.faces.size(); ++f) {
    const int k = r->objects.face[f];
    ASSERT_TRUE(k >= 0 && k < 3);
    ++faces[static_cast<std::size_t>(k)];
    Vec3 c = Vec3::Zero();
    for (int v : r->mesh.faces[f]) c += r->mesh.vertices[static_cast<std::size_t>(v)] / 3;
    EXPECT_EQ(k, c.x() > 5 ? 1 : c.y() > 5 ? 2 : 0);
  }
  EXPECT_EQ(faces, (std::array<int, 3>{12, 12, 12}));
  // One object: nothing to tell apart.
  ASSERT_TRUE(write_3mf(dir / "one.3mf", test::box({0, 0, 0}, {1, 1, 1})));
  auto one = load_mesh(dir / "one.3mf", test::unplaced(), {});
  ASSERT_TRUE(one);
  EXPECT_FALSE(one->objects.several());
  EXPECT_TRUE(one->objects.face.empty());
}

TEST(ThreeMfErrors, ZipThatIsNot3mfAndRandomBytes) {
  const auto dir = test::temp_dir("3mf_bad");
  // A valid zip (stored, one empty file "a.txt"), but no 3MF model inside.
  const unsigned char zip[] = {
      0x50, 0x4b, 0x03, 0x04, 0x0a, 0,    0,    0,    0,    0,    0,    0, 0x21, 0, 0,   0,
      0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0x05, 0, 0,    0, 'a', '.',
      't',  'x',  't',  0x50, 0x4b, 0x01, 0x02, 0x14, 0,    0x0a, 0,    0, 0,    0, 0,   0,
      0,    0x21, 0,    0,    0,    0,    0,    0,    0,    0,    0,    0, 0,    0, 0,   0x05,
      0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0, 0,    0, 0,   0,
      0,    0,    'a',  '.',  't',  'x',  't',  0x50, 0x4b, 0x05, 0x06, 0, 0,    0, 0,   0x01,
      0,    0x01, 0,    0x33, 0,    0,    0,    0x23, 0,    0,    0,    0, 0};
  test::write_bytes(dir / "zip.3mf", std::string(reinterpret_cast<const char*>(zip), sizeof zip));
  auto r = load_mesh(dir / "zip.3mf", {}, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::parse_error);
  EXPECT_NE(r.error().message.find("not a valid 3MF"), std::string::npos) << r.error().message;
  EXPECT_FALSE(io::parse_3mf("this is not a zip at all"));
  EXPECT_FALSE(io::parse_3mf(""));
}

// Hostile-input #9: nested components that expand past the triangle limit are refused after
// counting, before anything is built (the old reader built 5.5 GB first). 7 levels of 10
// components of a 12-triangle cube: 1.2e8 triangles, from a file of a few KB. (lib3mf's own
// reader walks the expanded tree once per object: 9 levels take it 37 s before we count.)
TEST(ThreeMfErrors, ComponentBombIsCountedNotBuilt) {
  const auto dir = test::temp_dir("3mf_bomb");
  NMR::PLib3MFModel* model = nullptr;
  ASSERT_EQ(NMR::lib3mf_createmodel(&model), 0);
  NMR::PLib3MFModelObjectResource* level = add_cube(model);
  std::vector<NMR::PLib3MFBase*> owned{level};
  for (int depth = 0; depth < 7; ++depth) {
    NMR::PLib3MFModelComponentsObject* up = nullptr;
    ASSERT_EQ(NMR::lib3mf_model_addcomponentsobject(model, &up), 0);
    owned.push_back(up);
    for (int i = 0; i < 10; ++i) {
      NMR::MODELTRANSFORM m = identity();
      m.m_fFields[0][3] = static_cast<float>(i);
      NMR::PLib3MFModelComponent* c = nullptr;
      ASSERT_EQ(NMR::lib3mf_componentsobject_addcomponent(up, level, &m, &c), 0);
      NMR::lib3mf_release(c);
    }
    level = up;
  }
  NMR::PLib3MFModelBuildItem* item = nullptr;
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, level, nullptr, &item), 0);
  const std::string bytes = write_model(model, dir / "bomb.3mf");
  NMR::lib3mf_release(item);
  for (auto* o : owned) NMR::lib3mf_release(o);
  NMR::lib3mf_release(model);
  EXPECT_LT(bytes.size(), 20000u);
  auto r = io::parse_3mf(bytes);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::invalid_mesh);
  EXPECT_NE(r.error().message.find("1.2e+08 triangles"), std::string::npos) << r.error().message;
}

// Hostile-input #12: a NaN transform got through (analyze: "volume nan"), and the unit
// attribute was ignored.
TEST(ThreeMfErrors, NonFiniteTransformsAndUnits) {
  const auto dir = test::temp_dir("3mf_units");
  for (const auto& [unit, mm] : {std::pair{NMR::MODELUNIT_INCH, 25.4},
                                 {NMR::MODELUNIT_MICROMETER, 0.001},
                                 {NMR::MODELUNIT_CENTIMETER, 10.0},
                                 {NMR::MODELUNIT_MILLIMETER, 1.0}}) {
    NMR::PLib3MFModel* model = nullptr;
    ASSERT_EQ(NMR::lib3mf_createmodel(&model), 0);
    ASSERT_EQ(NMR::lib3mf_model_setunit(model, unit), 0);
    auto* cube = add_cube(model);
    NMR::PLib3MFModelBuildItem* item = nullptr;
    ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, cube, nullptr, &item), 0);
    const std::string bytes = write_model(model, dir / "u.3mf");
    for (auto* p : {static_cast<NMR::PLib3MFBase*>(item), cube, model}) NMR::lib3mf_release(p);
    auto r = io::parse_3mf(bytes);
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_NEAR(signed_volume(*r), mm * mm * mm, 1e-9 * mm * mm * mm) << unit;
    EXPECT_TRUE(io::parse_3mf(bytes, 12));  // the count is exact: 12 triangles
    EXPECT_FALSE(io::parse_3mf(bytes, 11));
  }
  NMR::PLib3MFModel* model = nullptr;
  ASSERT_EQ(NMR::lib3mf_createmodel(&model), 0);
  auto* cube = add_cube(model);
  NMR::MODELTRANSFORM m = identity();
  m.m_fFields[1][1] = std::numeric_limits<float>::quiet_NaN();
  NMR::PLib3MFModelBuildItem* item = nullptr;
  ASSERT_EQ(NMR::lib3mf_model_addbuilditem(model, cube, &m, &item), 0);
  const std::string bytes = write_model(model, dir / "nan.3mf");
  for (auto* p : {static_cast<NMR::PLib3MFBase*>(item), cube, model}) NMR::lib3mf_release(p);
  auto r = io::parse_3mf(bytes);
  ASSERT_FALSE(r) << "a NaN transform was read";
  EXPECT_NE(r.error().message.find("not finite"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace nonplanar
