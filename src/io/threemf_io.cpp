// 3MF reading and writing through lib3mf 1.8's C interface (Debian's lib3mf-dev), loaded when
// first needed (lib3mf_api.hpp).
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/file_bytes.hpp"
#include "io/lib3mf_api.hpp"
#include "io/readers.hpp"
#include "io/threemf_prescan.hpp"
#include "io/zip_package.hpp"

namespace nonplanar::io {
namespace {

using Affine = Eigen::Affine3d;

// Owns one lib3mf handle and releases it.
struct Handle {
  NMR::PLib3MFBase* p = nullptr;
  Handle() = default;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (p) lib3mf().release(p);
  }
};

std::string last_error(NMR::PLib3MFBase* obj) {
  DWORD code = 0;
  LPCSTR msg = nullptr;
  if (obj && lib3mf().getlasterror(obj, &code, &msg) == 0 && msg && *msg) return msg;
  return "lib3mf error";
}

Affine to_affine(const NMR::MODELTRANSFORM& m) {
  // lib3mf stores rows of the 3x4 matrix [R | t]: x' = R x + t.
  Affine a = Affine::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) a.matrix()(r, c) = m.m_fFields[r][c];
  return a;
}

// Triangles an object holds once its components are expanded, without building anything: a
// 1.3 KB file of nested components once reached the limit only after 5.5 GB were built.
// Memoised per resource id; a double, since 20 levels of 10 components overflow 64 bits.
bool count_triangles(NMR::PLib3MFModelObjectResource* obj, int depth,
                     std::unordered_map<DWORD, double>& memo, double* count, std::string* err) {
  if (depth > 32) {
    *err = "components nested more than 32 deep (cycle?)";
    return false;
  }
  DWORD id = 0;
  const bool has_id = lib3mf().resource_getresourceid(obj, &id) == 0;
  if (has_id)
    if (auto it = memo.find(id); it != memo.end()) return *count = it->second, true;
  BOOL is_mesh = false, is_comp = false;
  lib3mf().object_ismeshobject(obj, &is_mesh);
  lib3mf().object_iscomponentsobject(obj, &is_comp);
  double total = 0;
  if (is_mesh) {
    DWORD nt = 0;
    if (lib3mf().meshobject_gettrianglecount(obj, &nt) != 0) return *err = last_error(obj), false;
    total = nt;
  } else if (is_comp) {
    DWORD n = 0;
    lib3mf().componentsobject_getcomponentcount(obj, &n);
    for (DWORD i = 0; i < n; ++i) {
      Handle comp, child;
      if (lib3mf().componentsobject_getcomponent(obj, i, &comp.p) != 0 ||
          lib3mf().component_getobjectresource(comp.p, &child.p) != 0)
        return *err = last_error(obj), false;
      double c = 0;
      if (!count_triangles(child.p, depth + 1, memo, &c, err)) return false;
      total += c;
    }
  }
  if (has_id) memo[id] = total;
  *count = total;
  return true;
}

// Millimetres per unit of the model's `unit` attribute (3MF core spec §3.4.1).
double unit_in_mm(DWORD unit) {
  switch (unit) {
    case NMR::MODELUNIT_MICROMETER:
      return 0.001;
    case NMR::MODELUNIT_CENTIMETER:
      return 10.0;
    case NMR::MODELUNIT_INCH:
      return 25.4;
    case NMR::MODELUNIT_FOOT:
      return 304.8;
    case NMR::MODELUNIT_METER:
      return 1000.0;
    default:
      return 1.0;
  }
}

// Appends an object (mesh or components, recursively) under transform `xf`.
bool append_object(NMR::PLib3MFModelObjectResource* obj, const Affine& xf, TriangleMesh& out,
                   int depth, std::string* err) {
  if (depth > 32) {
    *err = "components nested more than 32 deep (cycle?)";
    return false;
  }
  BOOL is_mesh = false, is_comp = false;
  lib3mf().object_ismeshobject(obj, &is_mesh);
  lib3mf().object_iscomponentsobject(obj, &is_comp);
  if (is_mesh) {
    DWORD nv = 0, nt = 0;
    if (lib3mf().meshobject_getvertexcount(obj, &nv) != 0 ||
        lib3mf().meshobject_gettrianglecount(obj, &nt) != 0) {
      *err = last_error(obj);
      return false;
    }
    std::vector<NMR::MODELMESHVERTEX> verts(nv);
    std::vector<NMR::MODELMESHTRIANGLE> tris(nt);
    if ((nv && lib3mf().meshobject_getvertices(obj, verts.data(), nv, nullptr) != 0) ||
        (nt && lib3mf().meshobject_gettriangleindices(obj, tris.data(), nt, nullptr) != 0)) {
      *err = last_error(obj);
      return false;
    }
    const int base = static_cast<int>(out.vertices.size());
    for (const auto& v : verts) {
      const Vec3 p(v.m_fPosition[0], v.m_fPosition[1], v.m_fPosition[2]);
      if (!p.allFinite()) {
        *err = "vertex coordinate is not a finite number";
        return false;
      }
      out.vertices.push_back(xf * p);
    }
    for (const auto& t : tris) {
      for (DWORD i : t.m_nIndices)
        if (i >= nv) {
          *err = "triangle index " + std::to_string(i) + " out of range";
          return false;
        }
      out.faces.push_back({base + static_cast<int>(t.m_nIndices[0]),
                           base + static_cast<int>(t.m_nIndices[1]),
                           base + static_cast<int>(t.m_nIndices[2])});
    }
    return true;
  }
  if (is_comp) {
    DWORD n = 0;
    lib3mf().componentsobject_getcomponentcount(obj, &n);
    for (DWORD i = 0; i < n; ++i) {
      Handle comp, child;
      if (lib3mf().componentsobject_getcomponent(obj, i, &comp.p) != 0 ||
          lib3mf().component_getobjectresource(comp.p, &child.p) != 0) {
        *err = last_error(obj);
        return false;
      }
      Affine cxf = Affine::Identity();
      BOOL has = false;
      lib3mf().component_hastransform(comp.p, &has);
      if (has) {
        NMR::MODELTRANSFORM m;
        lib3mf().component_gettransform(comp.p, &m);
        cxf = to_affine(m);
        if (!cxf.matrix().allFinite()) return *err = "a component's transform is not finite", false;
      }
      if (!append_object(child.p, xf * cxf, out, depth + 1, err)) return false;
    }
  }
  return true;
}

// The object's name as the 3MF gives it ("" when none).
std::string object_name(NMR::PLib3MFModelObjectResource* obj) {
  ULONG need = 0;
  if (lib3mf().object_getnameutf8(obj, nullptr, 0, &need) != 0 || need == 0) return "";
  std::string s(need + 1, '\0');
  if (lib3mf().object_getnameutf8(obj, s.data(), static_cast<ULONG>(s.size()), &need) != 0)
    return "";
  s.resize(std::min<std::size_t>(std::strlen(s.c_str()), 200));
  return s;
}

// Object names the slicers keep beside the model: PrusaSlicer's
// Metadata/Slic3r_PE_model.config (<object id="1" instances_count="2"> <metadata type="object"
// key="name" value="cube.stl"/>: model objects 1 and 2 are its two instances), and OrcaSlicer's
// and Bambu Studio's Metadata/model_settings.config (<object id="2"> <metadata key="name"
// value="Cube"/>). PrusaSlicer leaves the model's own name attribute out.
struct ConfigObject {
  DWORD id = 0, instances = 1;
  std::string name;
  /// Its volumes that are no part (modifiers, support blockers and enforcers, negative
  /// volumes): their first and last triangle in the object's mesh.
  std::vector<std::pair<std::size_t, std::size_t>> not_part;
};

// The triangle ranges of an object's volumes whose type is not a model part (PrusaSlicer:
// key "volume_type" other than "ModelPart", or the older "modifier" = 1).
std::vector<std::pair<std::size_t, std::size_t>> volumes_not_part(std::string_view obj) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  const std::string_view open = "<volume firstid=\"";
  for (std::size_t at = obj.find(open); at != std::string_view::npos; at = obj.find(open, at + 1)) {
    const std::size_t end = std::min(obj.find("</volume>", at), obj.size());
    const std::string_view v = obj.substr(at, end - at);
    const bool part =
        v.find("key=\"volume_type\"") == std::string_view::npos
            ? v.find("key=\"modifier\" value=\"1\"") == std::string_view::npos
            : v.find("key=\"volume_type\" value=\"ModelPart\"") != std::string_view::npos;
    const std::size_t last = v.find("lastid=\"");
    if (part || last == std::string_view::npos) continue;
    const unsigned long first = std::strtoul(v.data() + open.size(), nullptr, 10);
    const unsigned long final = std::strtoul(v.data() + last + 8, nullptr, 10);
    if (first <= final) out.emplace_back(first, final);
  }
  return out;
}
std::vector<ConfigObject> config_objects(std::string_view zip) {
  std::vector<ConfigObject> out;
  for (const char* entry : {"Metadata/Slic3r_PE_model.config", "Metadata/model_settings.config"}) {
    const auto text = zip_entry(zip, entry, std::size_t(64) << 20);
    if (!text) continue;
    const std::string_view s = *text;
    const std::string_view open = "<object id=\"";
    for (std::size_t at = s.find(open); at != std::string_view::npos; at = s.find(open, at + 1)) {
      const std::size_t end = s.find("</object>", at);
      const std::string_view obj = s.substr(at, end == std::string_view::npos ? 0 : end - at);
      const std::size_t key = obj.find("key=\"name\" value=\"");
      ConfigObject c;
      if (key != std::string_view::npos) {
        const std::size_t v0 = key + 18, v1 = obj.find('"', v0);
        if (v1 == std::string_view::npos) continue;
        c.name = std::string(obj.substr(v0, std::min<std::size_t>(v1 - v0, 200)));
      }
      c.id = static_cast<DWORD>(std::strtoul(obj.data() + open.size(), nullptr, 10));
      const std::size_t n = obj.substr(0, obj.find('>')).find("instances_count=\"");
      if (n != std::string_view::npos)
        c.instances = static_cast<DWORD>(
            std::clamp(std::strtoul(obj.data() + n + 17, nullptr, 10), 1ul, 1000000ul));
      c.not_part = volumes_not_part(obj);
      out.push_back(std::move(c));
    }
  }
  return out;
}

// Whose instance a build item is: PrusaSlicer's object (by its config) or else the model's
// own object resource; its name and number, and which copy.
class ItemNames {
 public:
  explicit ItemNames(std::string_view zip) : config_(config_objects(zip)) {
    // By first id, each found in log time (a hostile plate may hold a million objects).
    std::stable_sort(config_.begin(), config_.end(),
                     [](const ConfigObject& a, const ConfigObject& b) { return a.id < b.id; });
  }
  PlateObject next(NMR::PLib3MFModelObjectResource* obj, std::size_t item) {
    PlateObject p;
    p.name = object_name(obj);
    const ConfigObject* c = config_of(obj);
    // The config object's index, else the resource itself.
    const std::uint64_t source =
        c ? static_cast<std::uint64_t>(c - config_.data()) : (std::uint64_t(1) << 32) | id_of(obj);
    if (c && p.name.empty()) p.name = c->name;
    if (p.name.empty()) p.name = "object " + std::to_string(item + 1);
    const auto [it, fresh] = ids_.emplace(source, static_cast<int>(ids_.size()));
    p.id = it->second;
    p.copy = copies_[source]++;
    return p;
  }
  /// The object's triangles that are no part (ConfigObject::not_part); empty when none.
  const std::vector<std::pair<std::size_t, std::size_t>>& not_part(
      NMR::PLib3MFModelObjectResource* obj) const {
    static const std::vector<std::pair<std::size_t, std::size_t>> kNone;
    const ConfigObject* c = config_of(obj);
    return c ? c->not_part : kNone;
  }

 private:
  static DWORD id_of(NMR::PLib3MFModelObjectResource* obj) {
    DWORD id = 0;
    lib3mf().resource_getresourceid(obj, &id);
    return id;
  }
  // The config object with the greatest first id at or below this one, if it reaches it.
  const ConfigObject* config_of(NMR::PLib3MFModelObjectResource* obj) const {
    const DWORD id = id_of(obj);
    auto c = std::upper_bound(config_.begin(), config_.end(), id,
                              [](DWORD v, const ConfigObject& o) { return v < o.id; });
    if (c != config_.begin() && id - (--c)->id < c->instances) return &*c;
    return nullptr;
  }

  std::vector<ConfigObject> config_;
  std::unordered_map<std::uint64_t, int> ids_, copies_;
};

// The object just appended (its vertices and faces from first_vertex, first_face) without
// the faces of `ranges` (its triangle numbers) and the vertices only they used: a modifier or
// a support blocker is no part of what prints.
void drop_volumes(TriangleMesh& m, std::size_t first_vertex, std::size_t first_face,
                  const std::vector<std::pair<std::size_t, std::size_t>>& ranges) {
  if (ranges.empty()) return;
  std::vector<char> dropped(m.faces.size() - first_face, 0);
  for (const auto& [a, b] : ranges)
    for (std::size_t f = a; f <= b && f < dropped.size(); ++f) dropped[f] = 1;
  const std::vector<Vec3> old(m.vertices.begin() + static_cast<long>(first_vertex),
                              m.vertices.end());
  m.vertices.resize(first_vertex);
  std::vector<int> renumbered(old.size(), -1);
  std::size_t faces = first_face;
  for (std::size_t f = first_face; f < m.faces.size(); ++f) {
    if (dropped[f - first_face]) continue;
    for (int& v : m.faces[f]) {
      int& r = renumbered[static_cast<std::size_t>(v) - first_vertex];
      if (r < 0) {
        r = static_cast<int>(m.vertices.size());
        m.vertices.push_back(old[static_cast<std::size_t>(v) - first_vertex]);
      }
      v = r;
    }
    m.faces[faces++] = m.faces[f];
  }
  m.faces.resize(faces);
}

Expected<TriangleMesh> parse_package(std::string_view data, std::size_t max_triangles,
                                     PlateObjects* objects) {
  Handle model, reader;
  if (lib3mf().createmodel(&model.p) != 0 ||
      lib3mf().model_queryreader(model.p, "3mf", &reader.p) != 0)
    return Error{Status::internal_error, "cannot create a lib3mf reader"};
  std::vector<BYTE> buf(data.begin(), data.end());
  if (lib3mf().reader_readfrombuffer(reader.p, buf.data(), buf.size()) != 0)
    return Error{Status::parse_error, "not a valid 3MF file (" + last_error(reader.p) + ")"};
  Handle items;
  if (lib3mf().model_getbuilditems(model.p, &items.p) != 0)
    return Error{Status::parse_error, "3MF build has no items"};
  TriangleMesh mesh;
  BOOL has_next = false;
  std::string err;
  // Pass 1: count; pass 2 (a fresh iterator): build.
  std::unordered_map<DWORD, double> memo;
  double triangles = 0;
  while (lib3mf().builditemiterator_movenext(items.p, &has_next) == 0 && has_next) {
    Handle item, obj;
    if (lib3mf().builditemiterator_getcurrent(items.p, &item.p) != 0 ||
        lib3mf().builditem_getobjectresource(item.p, &obj.p) != 0)
      return Error{Status::parse_error, "3MF build item: " + last_error(items.p)};
    double c = 0;
    if (!count_triangles(obj.p, 0, memo, &c, &err))
      return Error{Status::parse_error, "3MF object: " + err};
    triangles += c;
    if (triangles > static_cast<double>(max_triangles)) {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "the build expands to %.3g triangles, over the limit of %zu (nested "
                    "components?)",
                    triangles, max_triangles);
      return Error{Status::invalid_mesh, msg};
    }
  }
  Handle again;
  if (lib3mf().model_getbuilditems(model.p, &again.p) != 0)
    return Error{Status::parse_error, "3MF build has no items"};
  ItemNames names(data);
  mesh.vertices.reserve(static_cast<std::size_t>(3 * triangles));
  mesh.faces.reserve(static_cast<std::size_t>(triangles));
  while (lib3mf().builditemiterator_movenext(again.p, &has_next) == 0 && has_next) {
    Handle item, obj;
    if (lib3mf().builditemiterator_getcurrent(again.p, &item.p) != 0 ||
        lib3mf().builditem_getobjectresource(item.p, &obj.p) != 0)
      return Error{Status::parse_error, "3MF build item: " + last_error(again.p)};
    Affine xf = Affine::Identity();
    BOOL has = false;
    lib3mf().builditem_hasobjecttransform(item.p, &has);
    if (has) {
      NMR::MODELTRANSFORM m;
      lib3mf().builditem_getobjecttransform(item.p, &m);
      xf = to_affine(m);
      if (!xf.matrix().allFinite())
        return Error{Status::parse_error, "3MF build item: its transform is not finite"};
    }
    const std::size_t first_vertex = mesh.vertices.size(), first_face = mesh.faces.size();
    if (!append_object(obj.p, xf, mesh, 0, &err))
      return Error{Status::parse_error, "3MF object: " + err};
    drop_volumes(mesh, first_vertex, first_face, names.not_part(obj.p));
    if (objects) {
      objects->face.resize(mesh.faces.size(), static_cast<int>(objects->items.size()));
      objects->items.push_back(names.next(obj.p, objects->items.size()));
    }
  }
  DWORD unit = NMR::MODELUNIT_MILLIMETER;
  lib3mf().model_getunit(model.p, &unit);
  if (const double mm = unit_in_mm(unit); mm != 1.0)
    for (Vec3& v : mesh.vertices) v *= mm;
  if (mesh.faces.empty()) return Error{Status::invalid_mesh, "3MF build holds no triangles"};
  return mesh;
}

}  // namespace

// More component paths than this are a bomb whatever their triangles (empty meshes nested
// deep would still cost lib3mf a walk per path).
constexpr double kMaxInstances = 1e6;

Expected<TriangleMesh> parse_3mf(std::string_view data, std::size_t max_triangles,
                                 PlateObjects* objects) {
  if (data.empty()) return Error{Status::parse_error, "file is empty"};
  // Counted from the XML before lib3mf reads it (it walks nested components once per object,
  // and cannot be cancelled): a 9-level bomb of a few KB took it 37 s.
  if (const auto pre = prescan_3mf(data)) {
    char msg[200];
    if (!pre->error.empty()) return Error{Status::parse_error, "3MF model: " + pre->error};
    if (pre->triangles > static_cast<double>(max_triangles) || pre->instances > kMaxInstances) {
      std::snprintf(msg, sizeof msg,
                    "the build expands to %.3g triangles in %.3g object instances, over the "
                    "limit of %zu triangles or %.0g instances (nested components?)",
                    pre->triangles, pre->instances, max_triangles, kMaxInstances);
      return Error{Status::invalid_mesh, msg};
    }
  }
  if (std::string why; !load_lib3mf(&why)) return Error{Status::io_error, why};
  PlateObjects found;
  auto r = parse_package(data, max_triangles, &found);
  if (r || r.error().message.rfind("not a valid 3MF file", 0) != 0) {
    if (r && objects) *objects = std::move(found);
    return r;
  }
  // A package lib3mf refuses for a part it names but lacks (PrusaSlicer's command line names
  // a thumbnail it never wrote): read again without such relationships.
  if (auto fixed = drop_dangling_relationships(data, nullptr))
    if (auto again = parse_package(*fixed, max_triangles, &(found = {}))) {
      if (objects) *objects = std::move(found);
      return again;
    }
  return r;
}

}  // namespace nonplanar::io

namespace nonplanar {

namespace {

std::string xml_escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// PrusaSlicer's per-object configuration for object `id` (its name and settings, one volume
// of the part's faces, then one per support blocker).
std::string slic3r_model_config(unsigned id, std::size_t faces, const Object3mf& o) {
  std::string s = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<config>\n <object id=\"" +
                  std::to_string(id) + "\" instances_count=\"1\">\n";
  auto meta = [&](const char* type, const std::string& k, const std::string& v) {
    s += std::string("  <metadata type=\"") + type + "\" key=\"" + xml_escaped(k) + "\" value=\"" +
         xml_escaped(v) + "\"/>\n";
  };
  if (!o.name.empty()) meta("object", "name", o.name);
  for (const auto& [k, v] : o.settings) meta("object", k, v);
  s += "  <volume firstid=\"0\" lastid=\"" + std::to_string(faces ? faces - 1 : 0) + "\">\n";
  if (!o.name.empty())
    s += "   <metadata type=\"volume\" key=\"name\" value=\"" + xml_escaped(o.name) + "\"/>\n";
  s += "  </volume>\n";
  std::size_t first = faces;
  for (const TriangleMesh& b : o.support_blockers) {
    if (b.faces.empty()) continue;
    s += "  <volume firstid=\"" + std::to_string(first) + "\" lastid=\"" +
         std::to_string(first + b.faces.size() - 1) + "\">\n";
    s += "   <metadata type=\"volume\" key=\"name\" value=\"support blocker\"/>\n";
    s += "   <metadata type=\"volume\" key=\"volume_type\" value=\"SupportBlocker\"/>\n";
    s += "  </volume>\n";
    first += b.faces.size();
  }
  s += " </object>\n</config>\n";
  return s;
}

// The part, then the support blockers: the object's volumes in the order of its faces.
std::vector<const TriangleMesh*> all_volumes(const TriangleMesh& mesh, const Object3mf& o) {
  std::vector<const TriangleMesh*> out{&mesh};
  for (const TriangleMesh& b : o.support_blockers)
    if (!b.faces.empty()) out.push_back(&b);
  return out;
}

}  // namespace

Expected<void> write_3mf(const std::filesystem::path& file, const TriangleMesh& mesh,
                         const std::vector<PackageFile>& extra_files, const Object3mf& object) {
  std::vector<PackageFile> extra = extra_files;
  using io::Handle;
  using io::lib3mf;
  if (std::string why; !io::load_lib3mf(&why))
    return Error{Status::io_error, file.string() + ": " + why};
  Handle model, obj, item, writer;
  if (lib3mf().createmodel(&model.p) != 0 || lib3mf().model_addmeshobject(model.p, &obj.p) != 0)
    return Error{Status::internal_error, file.string() + ": cannot create a 3MF model"};
  std::vector<NMR::MODELMESHVERTEX> verts;
  std::vector<NMR::MODELMESHTRIANGLE> tris;
  for (const TriangleMesh* m : all_volumes(mesh, object)) {
    const auto base = static_cast<DWORD>(verts.size());
    for (const Vec3& v : m->vertices) {
      NMR::MODELMESHVERTEX w;
      for (int k = 0; k < 3; ++k) w.m_fPosition[k] = static_cast<float>(v[k]);
      verts.push_back(w);
    }
    for (const auto& f : m->faces) {
      NMR::MODELMESHTRIANGLE t;
      for (int k = 0; k < 3; ++k) t.m_nIndices[k] = base + static_cast<DWORD>(f[k]);
      tris.push_back(t);
    }
  }
  if (lib3mf().meshobject_setgeometry(obj.p, verts.data(), static_cast<DWORD>(verts.size()),
                                      tris.data(), static_cast<DWORD>(tris.size())) != 0 ||
      lib3mf().model_addbuilditem(model.p, obj.p, nullptr, &item.p) != 0 ||
      lib3mf().model_querywriter(model.p, "3mf", &writer.p) != 0)
    return Error{Status::internal_error, file.string() + ": " + io::last_error(model.p)};
  if (!object.name.empty() && lib3mf().object_setnameutf8(obj.p, object.name.c_str()) != 0)
    return Error{Status::internal_error, file.string() + ": " + io::last_error(model.p)};
  if (!object.name.empty() || !object.settings.empty() || !object.support_blockers.empty()) {
    DWORD id = 0;
    lib3mf().resource_getresourceid(obj.p, &id);
    extra.push_back(
        {"/Metadata/Slic3r_PE_model.config", slic3r_model_config(id, mesh.faces.size(), object)});
  }
  if (!extra.empty()) {
    lib3mf().model_addcustomcontenttypeutf8(model.p, "txt", "text/plain");
    lib3mf().model_addcustomcontenttypeutf8(model.p, "config", "text/xml");
    lib3mf().model_addcustomcontenttypeutf8(model.p, "json", "application/json");
  }
  for (const PackageFile& f : extra) {
    Handle att;
    std::string path = f.path, type = "http://schemas.nonplanar.org/3mf/attachment";
    std::vector<BYTE> bytes(f.content.begin(), f.content.end());
    if (lib3mf().model_addattachmentutf8(model.p, path.data(), type.data(), &att.p) != 0 ||
        lib3mf().attachment_readfrombuffer(att.p, bytes.data(), bytes.size()) != 0)
      return Error{Status::internal_error, file.string() + ": " + io::last_error(model.p)};
  }
  ULONG64 size = 0;
  if (lib3mf().writer_getstreamsize(writer.p, &size) != 0)
    return Error{Status::internal_error, file.string() + ": " + io::last_error(writer.p)};
  std::vector<BYTE> buf(size);
  if (lib3mf().writer_writetobuffer(writer.p, buf.data(), size) != 0)
    return Error{Status::internal_error, file.string() + ": " + io::last_error(writer.p)};
  return write_file_atomically(file, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
    return bool(out);
  });
}

Expected<std::string> read_3mf_part(const std::filesystem::path& file, const std::string& name) {
  auto bytes = core::read_file_bytes(file, std::size_t(1) << 31);
  if (!bytes) return Error{bytes.error().status, file.string() + ": " + bytes.error().message};
  auto part = io::zip_entry(bytes->view(), name);
  if (!part)
    return Error{Status::parse_error, file.string() + ": no " + name + " in it (is it a 3MF " +
                                          "written by nonplanar prepare?)"};
  return std::move(*part);
}

}  // namespace nonplanar
