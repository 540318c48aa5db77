#include <cstdint>
#include <cstring>
#include <ostream>

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
