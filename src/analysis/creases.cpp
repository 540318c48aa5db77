#include "analysis/creases.hpp"

#include <cmath>

namespace nonplanar::analysis {

std::vector<char> find_creases(const MeshTopology& topo, const FaceGeometry& geom,
                               const std::vector<char>& painted, double crease_angle_rad) {
  const double cos_crease = std::cos(crease_angle_rad);
  std::vector<char> crease(topo.across.size(), 0);
  for (std::size_t c = 0; c < crease.size(); ++c) {
    const std::size_t f = c / 3;
    const int g = topo.across[c];
    if (g < 0 || !painted[f] || !painted[g] || geom.degenerate[f] || geom.degenerate[g]) continue;
    crease[c] = geom.normals[f].dot(geom.normals[g]) < cos_crease;
  }
  return crease;
}

}  // namespace nonplanar::analysis
