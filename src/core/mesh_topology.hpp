// Edge adjacency of a triangle mesh: which face lies across each edge of each face.
#pragma once

#include <cstddef>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// Adjacency built once per mesh. Corner c = 3·f + k names the edge of face f that runs
/// from faces[f][k] to faces[f][(k+1) % 3].
struct MeshTopology {
  static constexpr int kOpen = -1;         ///< no face across the edge
  static constexpr int kNonManifold = -2;  ///< two or more faces across the edge

  std::vector<int> vertex_face_offsets;  ///< V+1 offsets into vertex_faces (CSR)
  std::vector<int> vertex_faces;         ///< faces around each vertex
  std::vector<int> across;               ///< 3F: neighbour face, kOpen or kNonManifold
  std::vector<char> same_direction;      ///< 3F: neighbour runs the edge the same way (bad winding)
  std::size_t open_edges = 0;
  std::size_t non_manifold_edges = 0;
  std::size_t inconsistent_edges = 0;
};

/// Build the adjacency in O(F · valence), in parallel. Faces must not repeat a vertex.
MeshTopology build_topology(const TriangleMesh& mesh);

/// Shells: connected components of faces that share a vertex (so pieces joined only by a
/// non-manifold edge are one shell). Returns F component ids in [0, *count).
std::vector<int> face_components(const TriangleMesh& mesh, int* count);

}  // namespace nonplanar
