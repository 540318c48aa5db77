#include <string>
#include <vector>

#include "io/mesh_buffer.hpp"
#include "io/readers.hpp"

namespace nonplanar::io {

Expected<TriangleMesh> parse_obj(std::string_view data) {
  if (data.empty()) return Error{Status::parse_error, "file is empty"};
  TriangleMesh mesh;
  Tokenizer tok(data);
  std::vector<long long> poly;
  std::vector<int> face_lines;  // line of each face, for range errors found at the end
  while (!tok.at_end()) {
    const std::string_view key = tok.next();
    const int line = tok.line();
    if (key == "v") {
      Vec3 v;
      for (int k = 0; k < 3; ++k) {
        const std::string_view num = tok.next();
        const auto d = tok.line() == line ? parse_double(num) : std::nullopt;
        if (!d)
          return parse_error_at(line, "vertex coordinate '" + std::string(num.substr(0, 40)) +
                                          "' is not a finite number");
        v[k] = *d;
      }
      mesh.vertices.push_back(v);
      tok.rest_of_line();  // optional w or vertex colour
    } else if (key == "f") {
      poly.clear();
      const std::string_view rest = tok.rest_of_line();
      Tokenizer items(rest);
      for (std::string_view item = items.next(); !item.empty(); item = items.next()) {
        const std::string_view idx = item.substr(0, item.find('/'));
        const auto i = parse_int(idx);
        if (!i || *i == 0)
          return parse_error_at(line, "face index '" + std::string(item.substr(0, 40)) +
                                          "' is not a valid vertex number");
        // Negative indices count back from the vertices defined so far.
        const long long abs = *i < 0 ? static_cast<long long>(mesh.vertices.size()) + *i + 1 : *i;
        if (abs < 1 || abs > (1LL << 31) - 1)
          return parse_error_at(line, "face index " + std::to_string(*i) + " is out of range");
        poly.push_back(abs - 1);
      }
      if (poly.size() < 3) return parse_error_at(line, "face has fewer than 3 vertices");
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
        mesh.faces.push_back(
            {static_cast<int>(poly[0]), static_cast<int>(poly[k]), static_cast<int>(poly[k + 1])});
        face_lines.push_back(line);
      }
    } else {
      tok.rest_of_line();  // vt, vn, g, o, s, usemtl, mtllib, l, comments, ...
    }
  }
  const auto n = static_cast<int>(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.faces.size(); ++i)
    for (int v : mesh.faces[i])
      if (v >= n)
        return parse_error_at(face_lines[i], "face index " + std::to_string(v + 1) +
                                                 " is out of range (" + std::to_string(n) +
                                                 " vertices)");
  if (mesh.faces.empty()) return Error{Status::invalid_mesh, "OBJ file has no faces"};
  return mesh;
}

}  // namespace nonplanar::io
