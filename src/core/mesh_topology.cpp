#include "core/mesh_topology.hpp"

#include "core/huge_pages.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <numeric>

namespace nonplanar {

BoundingBox bounding_box(const TriangleMesh& mesh) {
  BoundingBox box;
  for (const Vec3& p : mesh.vertices) box.extend(p);
  return box;
}

double signed_volume(const TriangleMesh& mesh) {
  // Sum of signed tetrahedra against the origin; exact for a closed mesh.
  double v = 0.0;
  for (const auto& f : mesh.faces) {
    const Vec3& a = mesh.vertices[f[0]];
    v += a.dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]]));
  }
  return v / 6.0;
}

MeshTopology build_topology(const TriangleMesh& mesh) {
  MeshTopology t;
  const int nv = static_cast<int>(mesh.vertices.size());
  const int nf = static_cast<int>(mesh.faces.size());
  assign_huge(t.vertex_face_offsets, nv + 1, 0);
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++t.vertex_face_offsets[f[k] + 1];
  std::partial_sum(t.vertex_face_offsets.begin(), t.vertex_face_offsets.end(),
                   t.vertex_face_offsets.begin());
  assign_huge(t.vertex_faces, t.vertex_face_offsets.back(), 0);
  {
    std::vector<int> fill(t.vertex_face_offsets.begin(), t.vertex_face_offsets.end() - 1);
    for (int fi = 0; fi < nf; ++fi)
      for (int k = 0; k < 3; ++k) t.vertex_faces[fill[mesh.faces[fi][k]]++] = fi;
  }

  assign_huge(t.across, 3 * static_cast<std::size_t>(nf), MeshTopology::kOpen);
  assign_huge(t.same_direction, 3 * static_cast<std::size_t>(nf), char{0});
  std::atomic<std::size_t> open{0}, nonman{0}, incons{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 4096), [&](const tbb::blocked_range<int>& r) {
    std::size_t l_open = 0, l_nonman = 0, l_incons = 0;
    for (int fi = r.begin(); fi != r.end(); ++fi) {
      const auto& f = mesh.faces[fi];
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        int matches = 0, other = -1, smallest = fi;
        bool same = false;
        for (int i = t.vertex_face_offsets[a]; i < t.vertex_face_offsets[a + 1]; ++i) {
          const int g = t.vertex_faces[i];
          if (g == fi) continue;
          const auto& gf = mesh.faces[g];
          for (int j = 0; j < 3; ++j) {
            if (gf[j] == a && gf[(j + 1) % 3] == b) {
              ++matches, other = g, same = true, smallest = std::min(smallest, g);
            } else if (gf[j] == b && gf[(j + 1) % 3] == a) {
              ++matches, other = g, same = false, smallest = std::min(smallest, g);
            }
          }
        }
        const std::size_t c = 3 * static_cast<std::size_t>(fi) + k;
        if (matches == 0) {
          ++l_open;
        } else if (matches == 1) {
          t.across[c] = other;
          t.same_direction[c] = same;
          if (same && fi < other) ++l_incons;
        } else {
          t.across[c] = MeshTopology::kNonManifold;
          // Count each non-manifold edge once, from its lowest-numbered face (a face with
          // three distinct vertices holds a given edge at one corner only).
          if (smallest == fi) ++l_nonman;
        }
      }
    }
    open += l_open;
    nonman += l_nonman;
    incons += l_incons;
  });
  t.open_edges = open;
  t.non_manifold_edges = nonman;
  t.inconsistent_edges = incons;
  return t;
}

namespace {
int find_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}
}  // namespace

std::vector<int> face_components(const TriangleMesh& mesh, int* count) {
  // Union-find over vertices: faces sharing an edge share its two vertices, and faces that
  // touch only at a non-manifold edge are still one piece of material.
  const int nv = static_cast<int>(mesh.vertices.size());
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& f : mesh.faces) {
    const int r0 = find_root(parent, f[0]);
    for (int k = 1; k < 3; ++k) {
      const int rk = find_root(parent, f[k]);
      if (rk != r0) parent[rk] = r0;
    }
  }
  std::vector<int> label(nv, -1);
  std::vector<int> comp(mesh.faces.size());
  int n = 0;
  for (std::size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const int r = find_root(parent, mesh.faces[fi][0]);
    if (label[r] < 0) label[r] = n++;
    comp[fi] = label[r];
  }
  if (count) *count = n;
  return comp;
}

}  // namespace nonplanar
