#include "analysis/patches.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace nonplanar::analysis {

std::vector<Patch> extract_patches(const TriangleMesh& mesh, const MeshTopology& topo,
                                   const FaceGeometry& geom, const std::vector<char>& painted,
                                   const std::vector<char>& discontinuous,
                                   const std::vector<char>& crease, const AnalysisParams& params,
                                   std::vector<int>* face_patch) {
  const std::size_t nf = mesh.faces.size();
  auto eligible = [&](int f) { return f >= 0 && painted[f] && !discontinuous[f]; };
  std::vector<int> label(nf, -1);
  std::vector<Patch> patches;
  std::vector<int> queue;
  for (std::size_t seed = 0; seed < nf; ++seed) {
    if (label[seed] >= 0 || !eligible(static_cast<int>(seed))) continue;
    const int id = static_cast<int>(patches.size());
    Patch p;
    label[seed] = id;
    queue.assign(1, static_cast<int>(seed));
    for (std::size_t qi = 0; qi < queue.size(); ++qi) {
      const int f = queue[qi];
      p.faces.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const std::size_t c = 3 * static_cast<std::size_t>(f) + k;
        const int g = topo.across[c];
        if (!eligible(g) || label[g] >= 0 || crease[c]) continue;
        label[g] = id;
        queue.push_back(g);
      }
    }
    // Statistics.
    p.xy_min = Vec2(1e300, 1e300);
    p.xy_max = Vec2(-1e300, -1e300);
    p.z_min = 1e300;
    p.z_max = -1e300;
    double max_cos_drop = 1.0;
    for (int f : p.faces) {
      p.area += geom.areas[f];
      for (int v : mesh.faces[f]) {
        const Vec3& q = mesh.vertices[v];
        p.xy_min = p.xy_min.cwiseMin(q.head<2>());
        p.xy_max = p.xy_max.cwiseMax(q.head<2>());
        p.z_min = std::min(p.z_min, q.z());
        p.z_max = std::max(p.z_max, q.z());
      }
      if (!geom.degenerate[f]) max_cos_drop = std::min(max_cos_drop, geom.normals[f].z());
    }
    p.max_slope_deg = std::acos(std::clamp(max_cos_drop, -1.0, 1.0)) * 180.0 / M_PI;
    if (p.area < params.min_patch_area)
      p.verdict = PatchVerdict::too_small;
    else if (p.z_max - p.z_min < params.min_layer_height)
      p.verdict = PatchVerdict::flat;
    else
      p.verdict = PatchVerdict::nonplanar;
    std::sort(p.faces.begin(), p.faces.end());
    patches.push_back(std::move(p));
  }
  // Largest first, and relabel faces to match.
  std::vector<int> order(patches.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return patches[a].area > patches[b].area; });
  std::vector<int> rank(patches.size());
  std::vector<Patch> sorted;
  sorted.reserve(patches.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<int>(i);
    sorted.push_back(std::move(patches[order[i]]));
  }
  if (face_patch) {
    face_patch->assign(nf, -1);
    for (std::size_t f = 0; f < nf; ++f)
      if (label[f] >= 0) (*face_patch)[f] = rank[label[f]];
  }
  return sorted;
}

}  // namespace nonplanar::analysis
