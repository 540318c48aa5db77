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

}  // namespace

std::string amf_text(const TriangleMesh& mesh, std::size_t* collapsed,
                     const std::vector<std::pair<std::string, std::string>>& metadata) {
  if (collapsed) *collapsed = 0;
  // Keyed by the floats' bits: -0.0f and 0.0f stay two vertices, as an STL reader comparing
  // bytes keeps them.
  using Key = std::array<std::uint32_t, 3>;
  std::unordered_map<Key, std::uint32_t, FloatTripleHash> index;
  index.reserve(mesh.vertices.size());
  std::string v, f;
  v.reserve(mesh.vertices.size() * 100);
  f.reserve(mesh.faces.size() * 56);
  char buf[160];
  auto key_of = [](const Vec3& p, float c[3]) {
    Key key;
    for (int k = 0; k < 3; ++k) {
      c[k] = static_cast<float>(p[k]);
      std::memcpy(&key[static_cast<std::size_t>(k)], &c[k], 4);
    }
    return key;
  };
  auto put = [&](char* e, const char* s) {
    while (*s) *e++ = *s++;
    return e;
  };
  for (const auto& face : mesh.faces) {
    float c[3][3];
    Key keys[3];
    for (int k = 0; k < 3; ++k) keys[k] = key_of(mesh.vertices[face[k]], c[k]);
    if (keys[0] == keys[1] || keys[1] == keys[2] || keys[0] == keys[2]) {
      if (collapsed) ++*collapsed;
      continue;
    }
    std::uint32_t id[3];
    for (int k = 0; k < 3; ++k) {
      const auto [it, added] = index.emplace(keys[k], static_cast<std::uint32_t>(index.size()));
      id[k] = it->second;
      if (!added) continue;
      // The float's own value as a double, in the fewest digits that read back as that
      // double: a reader parsing to float or to double, then to float, gets the float.
      const char* tags[3][2] = {{"<x>", "</x>"}, {"<y>", "</y>"}, {"<z>", "</z>"}};
      char* e = put(buf, "<vertex><coordinates>");
      for (int d = 0; d < 3; ++d) {
        e = put(e, tags[d][0]);
        e = std::to_chars(e, buf + sizeof buf, static_cast<double>(c[k][d])).ptr;
        e = put(e, tags[d][1]);
      }
      e = put(e, "</coordinates></vertex>\n");
      v.append(buf, e);
    }
    char* e = put(buf, "<triangle>");
    const char* tags[3][2] = {{"<v1>", "</v1>"}, {"<v2>", "</v2>"}, {"<v3>", "</v3>"}};
    for (int k = 0; k < 3; ++k) {
      e = put(e, tags[k][0]);
      e = std::to_chars(e, buf + sizeof buf, id[k]).ptr;
      e = put(e, tags[k][1]);
    }
    e = put(e, "</triangle>\n");
    f.append(buf, e);
  }
  std::string out =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<amf unit=\"millimeter\">\n"
      "<object id=\"1\">\n";
  for (const auto& [type, value] : metadata)
    out += "<metadata type=\"" + type + "\">" + value + "</metadata>\n";
  out.reserve(out.size() + v.size() + f.size() + 128);
  out += "<mesh>\n<vertices>\n";
  out += v;
  out += "</vertices>\n<volume>\n";
  out += f;
  out += "</volume>\n</mesh>\n</object>\n</amf>\n";
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
