#include <array>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <unordered_map>

#include "core/atomic_file.hpp"
#include "nonplanar/io.hpp"

namespace nonplanar {

Expected<void> write_stl(const std::filesystem::path& file, const TriangleMesh& mesh) {
  return write_file_atomically(file, [&](std::ostream& out) {
    char header[80] = "binary STL written by nonplanar";
    out.write(header, 80);
    const auto n = static_cast<std::uint32_t>(mesh.faces.size());
    out.write(reinterpret_cast<const char*>(&n), 4);
    char rec[50] = {};
    for (const auto& f : mesh.faces) {
      const Vec3& a = mesh.vertices[f[0]];
      const Vec3& b = mesh.vertices[f[1]];
      const Vec3& c = mesh.vertices[f[2]];
      const Vec3 nrm = (b - a).cross(c - a).normalized();
      float v[12];
      for (int k = 0; k < 3; ++k) {
        v[k] = static_cast<float>(nrm[k]);
        v[3 + k] = static_cast<float>(a[k]);
        v[6 + k] = static_cast<float>(b[k]);
        v[9 + k] = static_cast<float>(c[k]);
      }
      std::memcpy(rec, v, 48);
      out.write(rec, 50);
    }
    return bool(out);
  });
}

namespace {

struct FloatTripleHash {
  std::size_t operator()(const std::array<std::uint32_t, 3>& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint32_t v : k) h = (h ^ v) * 1099511628211ull;
    return static_cast<std::size_t>(h);
  }
};

char* put(char* e, const char* s) {
  while (*s) *e++ = *s++;
  return e;
}

// An AMF object's shared vertices and its volumes' triangles, as text.
class AmfMesh {
 public:
  explicit AmfMesh(std::size_t vertices) {
    index_.reserve(vertices);
    vertices_.reserve(vertices * 100);
  }
  // The faces of m as triangles appended to `f`; those whose corners collapse to one point
  // or an edge in float are left out and returned.
  std::size_t add_faces(const TriangleMesh& m, std::string& f) {
    std::size_t collapsed = 0;
    for (const auto& face : m.faces) {
      float c[3][3];
      Key keys[3];
      for (int k = 0; k < 3; ++k) keys[k] = key_of(m.vertices[face[k]], c[k]);
      if (keys[0] == keys[1] || keys[1] == keys[2] || keys[0] == keys[2]) {
        ++collapsed;
        continue;
      }
      char buf[160];
      char* e = put(buf, "<triangle>");
      const char* tags[3][2] = {{"<v1>", "</v1>"}, {"<v2>", "</v2>"}, {"<v3>", "</v3>"}};
      for (int k = 0; k < 3; ++k) {
        e = put(e, tags[k][0]);
        e = std::to_chars(e, buf + sizeof buf, id(keys[k], c[k])).ptr;
        e = put(e, tags[k][1]);
      }
      e = put(e, "</triangle>\n");
      f.append(buf, e);
    }
    return collapsed;
  }
  const std::string& vertices() const { return vertices_; }
  void free_vertices() { std::string().swap(vertices_); }

 private:
  // Keyed by the floats' bits: -0.0f and 0.0f stay two vertices, as an STL reader comparing
  // bytes keeps them.
  using Key = std::array<std::uint32_t, 3>;
  static Key key_of(const Vec3& p, float c[3]) {
    Key key;
    for (int k = 0; k < 3; ++k) {
      c[k] = static_cast<float>(p[k]);
      std::memcpy(&key[static_cast<std::size_t>(k)], &c[k], 4);
    }
    return key;
  }
  // The vertex's index, written the first time it is used.
  std::uint32_t id(const Key& key, const float c[3]) {
    const auto [it, added] = index_.emplace(key, static_cast<std::uint32_t>(index_.size()));
    if (!added) return it->second;
    // The float's own value as a double, in the fewest digits that read back as that
    // double: a reader parsing to float or to double, then to float, gets the float.
    const char* tags[3][2] = {{"<x>", "</x>"}, {"<y>", "</y>"}, {"<z>", "</z>"}};
    char buf[160];
    char* e = put(buf, "<vertex><coordinates>");
    for (int d = 0; d < 3; ++d) {
      e = put(e, tags[d][0]);
      e = std::to_chars(e, buf + sizeof buf, static_cast<double>(c[d])).ptr;
      e = put(e, tags[d][1]);
    }
    e = put(e, "</coordinates></vertex>\n");
    vertices_.append(buf, e);
    return it->second;
  }
  std::unordered_map<Key, std::uint32_t, FloatTripleHash> index_;
  std::string vertices_;
};

}  // namespace

std::string amf_text(const TriangleMesh& mesh, std::size_t* collapsed,
                     const std::vector<std::pair<std::string, std::string>>& metadata,
                     const std::vector<TriangleMesh>& support_blockers) {
  AmfMesh amf(mesh.vertices.size());
  std::vector<std::string> volumes(1 + support_blockers.size());
  // A triangle's line is 70 bytes at 7-digit ids ("<triangle><v1>1234567</v1>...</triangle>"):
  // reserved at 56, Benchy's 225 000 faces grew the text once, 22.6 MB beside 25.3 MB.
  volumes[0].reserve(mesh.faces.size() * 72);
  const std::size_t lost = amf.add_faces(mesh, volumes[0]);
  if (collapsed) *collapsed = lost;  // the part's: a blocker's lost faces lose no material
  for (std::size_t b = 0; b < support_blockers.size(); ++b)
    amf.add_faces(support_blockers[b], volumes[b + 1]);
  std::string out =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<amf unit=\"millimeter\">\n"
      "<object id=\"1\">\n";
  for (const auto& [type, value] : metadata)
    out += "<metadata type=\"" + type + "\">" + value + "</metadata>\n";
  std::size_t size = out.size() + amf.vertices().size() + 128 * volumes.size();
  for (const std::string& f : volumes) size += f.size();
  out.reserve(size);
  // Each part goes once copied: the text's pages are touched as it is written, so the whole
  // and every part were held at once only for the part being copied (the mesh's AMF three times
  // over at Benchy's engine-route peak).
  out += "<mesh>\n<vertices>\n";
  out += amf.vertices();
  amf.free_vertices();
  out += "</vertices>\n";
  for (std::size_t k = 0; k < volumes.size(); ++k) {
    out += "<volume>\n";
    // PrusaSlicer's AMF reader: a volume's type from its metadata, before its triangles.
    if (k > 0) out += "<metadata type=\"slic3r.volume_type\">SupportBlocker</metadata>\n";
    out += volumes[k];
    std::string().swap(volumes[k]);
    out += "</volume>\n";
  }
  out += "</mesh>\n</object>\n</amf>\n";
  return out;
}

Expected<void> write_ply_face_colors(const std::filesystem::path& file, const TriangleMesh& mesh,
                                     const std::vector<unsigned>& face_colors) {
  if (face_colors.size() != mesh.faces.size())
    return Error{Status::invalid_argument, "face_colors: one colour per face expected"};
  return write_file_atomically(file, [&](std::ostream& out) {
    out << "ply\nformat ascii 1.0\ncomment written by nonplanar: one colour per patch\n"
        << "element vertex " << mesh.vertices.size() << "\nproperty float x\nproperty float y\n"
        << "property float z\nelement face " << mesh.faces.size()
        << "\nproperty list uchar int vertex_indices\nproperty uchar red\nproperty uchar green\n"
        << "property uchar blue\nend_header\n";
    out.precision(9);
    for (const Vec3& v : mesh.vertices) out << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
      const auto& f = mesh.faces[i];
      const unsigned c = face_colors[i];
      out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << ' ' << ((c >> 16) & 255) << ' '
          << ((c >> 8) & 255) << ' ' << (c & 255) << '\n';
    }
    return bool(out);
  });
}

}  // namespace nonplanar
