#include "core/mesh_topology.hpp"
#include "core/parallel.hpp"

#include "core/huge_pages.hpp"

#include <algorithm>
#include <atomic>
#include <numeric>
#include <utility>

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

  // Each undirected edge is settled once, at its lower vertex: the half-edges of that
  // vertex's fan that end higher, sorted by their other end, come in groups of one edge.
  // O(F log valence) whatever the input: scanning the whole fan for every corner was
  // quadratic on duplicated facets (96k copies of one triangle took 86 s).
  assign_huge(t.across, 3 * static_cast<std::size_t>(nf), MeshTopology::kOpen);
  assign_huge(t.same_direction, 3 * static_cast<std::size_t>(nf), char{0});
  std::atomic<std::size_t> open{0}, nonman{0}, incons{0};
  core::parallel_blocks(int{0}, int(nv), int{1024}, [&](int r_begin, int r_end) {
    std::size_t l_open = 0, l_nonman = 0, l_incons = 0;
    std::vector<std::pair<int, int>> half;  // (higher end, corner 3·face + k)
    for (int a = r_begin; a != r_end; ++a) {
      half.clear();
      for (int i = t.vertex_face_offsets[a]; i < t.vertex_face_offsets[a + 1]; ++i) {
        const int g = t.vertex_faces[i];
        const auto& gf = mesh.faces[g];
        for (int j = 0; j < 3; ++j) {
          const int u = gf[j], v = gf[(j + 1) % 3];
          if (std::min(u, v) == a && u != v) half.emplace_back(std::max(u, v), 3 * g + j);
        }
      }
      std::sort(half.begin(), half.end());  // ties by corner: the same on any thread count
      half.erase(std::unique(half.begin(), half.end()), half.end());  // a face seen twice
      for (std::size_t i = 0; i < half.size();) {
        std::size_t j = i + 1;
        while (j < half.size() && half[j].first == half[i].first) ++j;
        if (j - i == 1) {
          ++l_open;
        } else if (j - i == 2) {
          const int c0 = half[i].second, c1 = half[i + 1].second;
          const bool same = mesh.faces[c0 / 3][c0 % 3] == mesh.faces[c1 / 3][c1 % 3];
          t.across[c0] = c1 / 3, t.across[c1] = c0 / 3;
          t.same_direction[c0] = t.same_direction[c1] = same;
          if (same) ++l_incons;
        } else {
          for (std::size_t m = i; m < j; ++m) t.across[half[m].second] = MeshTopology::kNonManifold;
          ++l_nonman;
        }
        i = j;
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
