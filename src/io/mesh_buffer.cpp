#include "io/mesh_buffer.hpp"

namespace nonplanar::io {

std::optional<Error> check_face_indices(const TriangleMesh& mesh) {
  const auto n = static_cast<long long>(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.faces.size(); ++i)
    for (int v : mesh.faces[i])
      if (v < 0 || v >= n)
        return Error{Status::parse_error, "face " + std::to_string(i + 1) + " uses vertex " +
                                              std::to_string(v + 1) + " but there are only " +
                                              std::to_string(n) + " vertices"};
  return std::nullopt;
}

}  // namespace nonplanar::io
