#include "analysis/facet_selection.hpp"
#include "core/parallel.hpp"

#include <cmath>

#include "core/huge_pages.hpp"

namespace nonplanar::analysis {

FaceGeometry face_geometry(const TriangleMesh& mesh) {
  const std::size_t nf = mesh.faces.size();
  FaceGeometry g;
  assign_huge(g.normals, nf, Vec3(Vec3::Zero()));
  assign_huge(g.areas, nf, 0.0);
  assign_huge(g.degenerate, nf, char{0});
  const double diag = bounding_box(mesh).size().norm();
  const double min_area = (1e-9 * diag) * (1e-9 * diag);
  core::parallel_blocks(std::size_t{0}, std::size_t(nf), std::size_t{8192},
                        [&](std::size_t r_begin, std::size_t r_end) {
                          for (std::size_t i = r_begin; i != r_end; ++i) {
                            const auto& f = mesh.faces[i];
                            const Vec3& a = mesh.vertices[f[0]];
                            const Vec3 c = (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a);
                            const double n = c.norm();
                            g.areas[i] = 0.5 * n;
                            g.degenerate[i] = g.areas[i] <= min_area;
                            g.normals[i] = g.degenerate[i] ? Vec3::Zero() : Vec3(c / n);
                          }
                        });
  return g;
}

std::vector<char> select_facets(const FaceGeometry& geom, const MeshTopology& topo,
                                double max_angle_rad) {
  const std::size_t nf = geom.normals.size();
  const double cos_max = std::cos(max_angle_rad);
  std::vector<char> painted(nf, 0);
  for (std::size_t i = 0; i < nf; ++i)
    painted[i] = !geom.degenerate[i] && geom.normals[i].z() > cos_max;
  for (std::size_t i = 0; i < nf; ++i) {
    if (!geom.degenerate[i]) continue;
    for (int k = 0; k < 3; ++k) {
      const int g = topo.across[3 * i + k];
      if (g >= 0 && !geom.degenerate[g] && painted[g]) painted[i] = 1;
    }
  }
  return painted;
}

}  // namespace nonplanar::analysis
