#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <unordered_map>
#include <unordered_set>

#include "core/parallel.hpp"
#include "nonplanar/deform.hpp"

namespace nonplanar {
namespace {

Vec3 mapped(const LayerField& f, const Vec3& p) {
  return {p.x(), p.y(), f.zeta(f.T(p.x(), p.y(), p.z()))};
}

std::uint64_t edge_key(int a, int b) {
  const auto [lo, hi] = std::minmax(a, b);
  return (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi);
}

}  // namespace

NormalizeParams shell_normalize_params(const TriangleMesh& mesh) {
  NormalizeParams p;
  p.max_faces = std::max<std::size_t>(500'000, 4 * mesh.faces.size());
  return p;
}

Expected<NormalizedMesh> normalize_mesh(const TriangleMesh& mesh, const LayerField& field,
                                        const NormalizeParams& params, const Context& ctx) {
  ctx.progress("normalize", 0);
  if (!std::isfinite(params.tolerance) || params.tolerance <= 0)
    return Error{Status::invalid_argument, "normalize tolerance: must be > 0"};
  NormalizedMesh out;
  TriangleMesh m = mesh;
  std::vector<Vec3> image(m.vertices.size());
  // Field evaluations are the cost (a root-find in blend zones): in parallel, then the
  // bookkeeping in order, so the result does not depend on the thread count.
  core::parallel_for(std::size_t{0}, m.vertices.size(),
                     [&](std::size_t v) { image[v] = mapped(field, m.vertices[v]); });

  // Edges already tested and kept whole keep their ends (vertices are only appended), so
  // the same test would keep them whole again: only edges made by a split are tested, and a
  // face no edge of which was split is final. (Re-testing every edge of the part every
  // round was most of this stage's time.)
  std::unordered_set<std::uint64_t> settled;
  std::vector<char> final_face(m.faces.size(), 0);
  for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
    Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
    for (int v : m.faces[fi])
      lo = lo.cwiseMin(m.vertices[v].head<2>()), hi = hi.cwiseMax(m.vertices[v].head<2>());
    final_face[fi] = (lo.array() > params.care_max.array()).any() ||
                     (hi.array() < params.care_min.array()).any();
    // Its edges stay whole for its neighbours too (conforming: no crack for the slicer).
    if (final_face[fi])
      for (int k = 0; k < 3; ++k)
        settled.insert(edge_key(m.faces[fi][k], m.faces[fi][(k + 1) % 3]));
  }
  for (int round = 0; round < params.max_rounds; ++round) {
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    // Decide per edge once; the midpoint index is shared by both faces (conforming).
    std::unordered_map<std::uint64_t, int> mid;
    std::vector<std::pair<int, int>> edges;  // each edge once, in face order
    for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
      if (final_face[fi]) continue;
      for (int k = 0; k < 3; ++k) {
        const int a = m.faces[fi][k], b = m.faces[fi][(k + 1) % 3];
        if (!settled.count(edge_key(a, b)) && mid.emplace(edge_key(a, b), -1).second)
          edges.emplace_back(a, b);
      }
    }
    std::vector<Vec3> im(edges.size());
    std::vector<char> split_it(edges.size());
    core::parallel_for(std::size_t{0}, edges.size(), [&](std::size_t e) {
      const auto [a, b] = edges[e];
      const Vec3 pm = 0.5 * (m.vertices[a] + m.vertices[b]);
      im[e] = mapped(field, pm);
      // Long edges in a curved region are split regardless: a midpoint on the chord does
      // not prove the whole edge maps straight.
      const bool long_curved = im[e].z() != pm.z() && (m.vertices[a] - m.vertices[b]).norm() > 2.0;
      split_it[e] = long_curved || (im[e] - 0.5 * (image[a] + image[b])).norm() > params.tolerance;
    });
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (!split_it[e]) {
        settled.insert(edge_key(edges[e].first, edges[e].second));
        continue;
      }
      const auto [a, b] = edges[e];
      mid[edge_key(a, b)] = static_cast<int>(m.vertices.size());
      m.vertices.push_back(0.5 * (m.vertices[a] + m.vertices[b]));
      image.push_back(im[e]);
    }
    std::size_t split = 0;
    std::vector<std::array<int, 3>> faces;
    std::vector<char> final_next;
    faces.reserve(m.faces.size());
    final_next.reserve(m.faces.size());
    for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
      const auto& f = m.faces[fi];
      int e[3] = {-1, -1, -1};
      int n = 0;
      if (!final_face[fi])
        for (int k = 0; k < 3; ++k) {
          const auto it = mid.find(edge_key(f[k], f[(k + 1) % 3]));
          n += (e[k] = it == mid.end() ? -1 : it->second) >= 0;
        }
      if (n == 0) {
        faces.push_back(f);
      } else if (n == 1) {
        const int k = e[0] >= 0 ? 0 : e[1] >= 0 ? 1 : 2;  // split edge f[k] → f[k+1]
        const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3], mab = e[k];
        faces.push_back({a, mab, c});
        faces.push_back({mab, b, c});
      } else if (n == 2) {
        const int u = e[0] < 0 ? 0 : e[1] < 0 ? 1 : 2;  // the edge that stays whole: a → b
        const int a = f[u], b = f[(u + 1) % 3], c = f[(u + 2) % 3];
        const int mbc = e[(u + 1) % 3], mca = e[(u + 2) % 3];
        faces.push_back({a, b, mbc});
        faces.push_back({a, mbc, mca});
        faces.push_back({mca, mbc, c});
      } else {
        const int a = f[0], b = f[1], c = f[2], mab = e[0], mbc = e[1], mca = e[2];
        faces.push_back({a, mab, mca});
        faces.push_back({mab, b, mbc});
        faces.push_back({mca, mbc, c});
        faces.push_back({mab, mbc, mca});
      }
      final_next.resize(faces.size(), n == 0);
    }
    for (const auto& [key, v] : mid) split += v >= 0;
    m.faces = std::move(faces);
    if (params.max_faces > 0 && m.faces.size() > params.max_faces) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "the map onto the curved layers would split the part into more than %zu "
                    "triangles (its top bends too sharply)",
                    params.max_faces);
      return Error{Status::unsupported, buf};
    }
    final_face = std::move(final_next);
    out.rounds = round + 1;
    out.edges_split += split;
    ctx.progress("normalize", std::min(1.0, 0.1 * (round + 1)));
    if (split == 0) break;
  }
  m.vertices = std::move(image);
  out.mesh = std::move(m);
  return out;
}

}  // namespace nonplanar
