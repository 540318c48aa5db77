#include "analysis/curvature.hpp"
#include "core/parallel.hpp"

#include <cmath>

namespace nonplanar::analysis {
namespace {

// Interior angle at corner k of face f, robust for slivers (atan2 rather than acos).
double corner_angle(const TriangleMesh& mesh, const std::array<int, 3>& f, int k) {
  const Vec3& a = mesh.vertices[f[k]];
  const Vec3 u = mesh.vertices[f[(k + 1) % 3]] - a;
  const Vec3 w = mesh.vertices[f[(k + 2) % 3]] - a;
  return std::atan2(u.cross(w).norm(), u.dot(w));
}

}  // namespace

std::vector<double> VertexCurvature::normalized() const {
  std::vector<double> k(deficit.size(), 0.0);
  for (std::size_t i = 0; i < k.size(); ++i)
    if (area[i] > 0) k[i] = deficit[i] / area[i];
  return k;
}

VertexCurvature angle_deficit(const TriangleMesh& mesh, const MeshTopology& topo,
                              const FaceGeometry& geom, const std::vector<char>* mask) {
  const std::size_t nv = mesh.vertices.size();
  VertexCurvature c;
  c.deficit.assign(nv, 0.0);
  c.area.assign(nv, 0.0);
  c.boundary.assign(nv, 0);
  auto in = [&](int f) { return f >= 0 && (!mask || (*mask)[f]); };
  // Gather per vertex over its faces: no two threads write the same vertex.
  core::parallel_blocks(
      std::size_t{0}, std::size_t(nv), std::size_t{4096},
      [&](std::size_t r_begin, std::size_t r_end) {
        for (std::size_t v = r_begin; v != r_end; ++v) {
          double theta = 0.0, area = 0.0;
          bool touched = false, boundary = false;
          for (int i = topo.vertex_face_offsets[v]; i < topo.vertex_face_offsets[v + 1]; ++i) {
            const int f = topo.vertex_faces[i];
            if (!in(f)) continue;
            touched = true;
            const auto& tri = mesh.faces[f];
            const int k = tri[0] == static_cast<int>(v) ? 0 : tri[1] == static_cast<int>(v) ? 1 : 2;
            theta += corner_angle(mesh, tri, k);
            area += geom.areas[f] / 3.0;
            // The two edges of f at v: corner k (v → next) and corner k+2 (prev → v).
            if (!in(topo.across[3 * f + k]) || !in(topo.across[3 * f + (k + 2) % 3]))
              boundary = true;
          }
          if (!touched) continue;
          c.boundary[v] = boundary;
          c.deficit[v] = (boundary ? M_PI : 2.0 * M_PI) - theta;
          c.area[v] = area;
        }
      });
  return c;
}

std::vector<char> discontinuous_vertices(const TriangleMesh& mesh, const VertexCurvature& curv,
                                         const std::vector<char>& mask, double tau,
                                         double epsilon) {
  const std::vector<double> k = curv.normalized();
  std::vector<char> out(mesh.vertices.size(), 0);
  auto interior = [&](int v) { return curv.area[v] > 0 && !curv.boundary[v]; };
  for (std::size_t v = 0; v < k.size(); ++v)
    if (interior(static_cast<int>(v)) && k[v] > tau) out[v] = 1;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!mask[f]) continue;
    for (int e = 0; e < 3; ++e) {
      const int a = mesh.faces[f][e], b = mesh.faces[f][(e + 1) % 3];
      if (interior(a) && interior(b) && std::abs(k[a] - k[b]) > epsilon) out[a] = out[b] = 1;
    }
  }
  return out;
}

}  // namespace nonplanar::analysis
