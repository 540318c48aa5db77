#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <utility>
#include <vector>

#include "core/parallel.hpp"
#include "nonplanar/deform.hpp"

namespace nonplanar {
namespace {

// z of p's image (x and y stay).
double mapped_z(const LayerField& f, const Vec3& p) {
  return f.zeta(f.T(p.x(), p.y(), p.z()));
}

std::uint64_t edge_key(int a, int b) {
  const auto [lo, hi] = std::minmax(a, b);
  return (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi);
}

// The edge of corner c = 3·f + k: faces[f][k] → faces[f][(k + 1) % 3].
std::uint64_t corner_key(const TriangleMesh& m, std::size_t c) {
  const auto& f = m.faces[c / 3];
  return edge_key(f[c % 3], f[(c + 1) % 3]);
}

// The edges a round tests: those of non-final faces' corners not yet settled, each once, in
// the order a walk over the faces meets them; and, per corner, the index of its edge there
// (-1: settled or final). Found by sorting (key, corner) pairs, not by hashing: a node-based
// hash of every edge held 102 MB on Benchy's shell.
struct RoundEdges {
  std::vector<std::pair<int, int>> edges;  ///< (a, b) of each edge, as its first corner runs
  std::vector<int> corner_edge;            ///< 3F
};
RoundEdges round_edges(const TriangleMesh& m, const std::vector<char>& final_face,
                       const std::vector<char>& settled) {
  // (edge key, corner), 12 bytes: the sort's array is this stage's peak (Benchy's shell).
  struct Half {
    std::uint32_t lo, hi, corner;
    bool operator<(const Half& o) const {
      return lo != o.lo ? lo < o.lo : hi != o.hi ? hi < o.hi : corner < o.corner;
    }
    bool same_edge(const Half& o) const { return lo == o.lo && hi == o.hi; }
  };
  // Sorted by a counting sort on lo (a vertex index), then each vertex's few by (hi, corner):
  // std::sort of the whole array was half of this stage on the sine roof (110 000 corners).
  const auto tested = [&](std::size_t c) { return !final_face[c / 3] && !settled[c]; };
  std::vector<std::uint32_t> start(m.vertices.size() + 1, 0);
  std::size_t count = 0;
  for (std::size_t c = 0; c < 3 * m.faces.size(); ++c)
    if (tested(c)) ++start[(corner_key(m, c) >> 32) + 1], ++count;
  for (std::size_t v = 1; v < start.size(); ++v) start[v] += start[v - 1];
  std::vector<Half> half(count);
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t c = 0; c < 3 * m.faces.size(); ++c)
      if (tested(c)) {
        const std::uint64_t k = corner_key(m, c);
        half[next[k >> 32]++] = {static_cast<std::uint32_t>(k >> 32), static_cast<std::uint32_t>(k),
                                 static_cast<std::uint32_t>(c)};
      }
  }
  for (std::size_t v = 0; v + 1 < start.size(); ++v)
    std::sort(half.begin() + start[v], half.begin() + start[v + 1]);
  // Each key's first corner (the least, as sorted) leads its edge; corner_edge holds the key's
  // rank among keys until the walk over the corners numbers the edges as their leaders come.
  RoundEdges r;
  r.corner_edge.assign(3 * m.faces.size(), -1);
  std::vector<std::uint32_t> leader;
  for (std::size_t h = 0; h < half.size(); ++h) {
    if (h == 0 || !half[h].same_edge(half[h - 1])) leader.push_back(half[h].corner);
    r.corner_edge[half[h].corner] = static_cast<int>(leader.size() - 1);
  }
  half = {};
  std::vector<int> number(leader.size(), -1);
  r.edges.reserve(leader.size());
  for (std::size_t c = 0; c < r.corner_edge.size(); ++c) {
    const int g = r.corner_edge[c];
    if (g < 0) continue;
    if (leader[static_cast<std::size_t>(g)] == c) {
      number[static_cast<std::size_t>(g)] = static_cast<int>(r.edges.size());
      const auto& f = m.faces[c / 3];
      r.edges.emplace_back(f[c % 3], f[(c + 1) % 3]);
    }
    r.corner_edge[c] = number[static_cast<std::size_t>(g)];
  }
  return r;
}

constexpr double kLongEdge = 2.0;  ///< mm: an edge longer than this is probed along its length

// Whether the map strays more than dz_max in z from the chord a → b (mapped za, zb) at any of
// the points every ≤ 1 mm along it.
bool strays(const LayerField& field, const Vec3& a, const Vec3& b, double za, double zb,
            double dz_max) {
  const int n = static_cast<int>(std::ceil((b - a).norm()));
  for (int i = 1; i < n; ++i) {
    const double s = static_cast<double>(i) / n;
    if (std::abs(mapped_z(field, a + s * (b - a)) - (za + s * (zb - za))) > dz_max) return true;
  }
  return false;
}

// Per edge of `r`: the largest |n_z| of the unit normals of its faces as mapped (z: `image`), 1
// for a face of no area. A wall takes the map's error in z across its plane only that much:
// the distance between the mapped mesh and the exact map is dz · |n_z|, and a steep wall's
// section moves by it, not by dz (the sphere's normalised mesh had 8 times its faces).
std::vector<float> flatness(const TriangleMesh& m, const std::vector<double>& image,
                            const std::vector<char>& final_face, const RoundEdges& r) {
  std::vector<float> flat(r.edges.size(), 0.0f);
  for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
    if (final_face[fi]) continue;
    const auto& f = m.faces[fi];
    auto at = [&](int v) { return Vec3(m.vertices[v].x(), m.vertices[v].y(), image[v]); };
    const Vec3 n = (at(f[1]) - at(f[0])).cross(at(f[2]) - at(f[0]));
    const double len = n.norm();
    const float nz = len > 0 ? static_cast<float>(std::abs(n.z()) / len) : 1.0f;
    for (std::size_t k = 0; k < 3; ++k) {
      const int e = r.corner_edge[3 * fi + k];
      if (e >= 0)
        flat[static_cast<std::size_t>(e)] = std::max(flat[static_cast<std::size_t>(e)], nz);
    }
  }
  return flat;
}

// Corners of non-final faces on an edge of a final face (outside the care box): settled, so
// the edge stays whole for both (conforming: no crack for the slicer).
std::vector<char> settled_by_final(const TriangleMesh& m, const std::vector<char>& final_face) {
  std::vector<std::uint64_t> keys;
  for (std::size_t c = 0; c < 3 * m.faces.size(); ++c)
    if (final_face[c / 3]) keys.push_back(corner_key(m, c));
  std::sort(keys.begin(), keys.end());
  std::vector<char> settled(3 * m.faces.size(), 0);
  if (keys.empty()) return settled;
  for (std::size_t c = 0; c < 3 * m.faces.size(); ++c)
    if (!final_face[c / 3])
      settled[c] = std::binary_search(keys.begin(), keys.end(), corner_key(m, c));
  return settled;
}

Error too_many(std::size_t max_faces) {
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "the map onto the curved layers would split the part into more than %zu "
                "triangles (its top bends too sharply)",
                max_faces);
  return Error{Status::unsupported, buf};
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
  std::vector<double> image(m.vertices.size());  // each vertex's z as mapped
  // Field evaluations are the cost (a root-find in blend zones): in parallel, then the
  // bookkeeping in order, so the result does not depend on the thread count.
  core::parallel_for(std::size_t{0}, m.vertices.size(),
                     [&](std::size_t v) { image[v] = mapped_z(field, m.vertices[v]); });

  // Edges already tested and kept whole keep their ends (vertices are only appended), so
  // the same test would keep them whole again: only edges made by a split are tested, and a
  // face no edge of which was split is final. (Re-testing every edge of the part every
  // round was most of this stage's time.) `settled` marks such edges per corner: both faces
  // of an edge inherit it from their parents, which shared it too.
  std::vector<char> final_face(m.faces.size(), 0);
  for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
    Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
    for (int v : m.faces[fi])
      lo = lo.cwiseMin(m.vertices[v].head<2>()), hi = hi.cwiseMax(m.vertices[v].head<2>());
    final_face[fi] = (lo.array() > params.care_max.array()).any() ||
                     (hi.array() < params.care_min.array()).any();
  }
  std::vector<char> settled = settled_by_final(m, final_face);
  for (int round = 0; round < params.max_rounds; ++round) {
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    // Decide per edge once; the midpoint index is shared by both faces (conforming).
    RoundEdges round_e = round_edges(m, final_face, settled);
    const std::vector<std::pair<int, int>>& edges = round_e.edges;
    const std::vector<float> flat = flatness(m, image, final_face, round_e);
    std::vector<double> im(edges.size());  // each edge's midpoint's z as mapped
    std::vector<char> split_it(edges.size());
    core::parallel_for(std::size_t{0}, edges.size(), [&](std::size_t e) {
      const auto [a, b] = edges[e];
      const Vec3 pm = 0.5 * (m.vertices[a] + m.vertices[b]);
      im[e] = mapped_z(field, pm);
      // The map moves a point only in z: the exact midpoint lies dz above the chord, and
      // dz · |n_z| from the faces' planes.
      const double dz = std::abs(im[e] - 0.5 * (image[a] + image[b]));
      split_it[e] = dz * flat[e] > params.tolerance;
      // A midpoint on the chord does not prove a long edge maps straight: in a curved region
      // it is probed every millimetre too (split regardless, the sine roof's and FoilCutter's
      // vertical sides made 1644 and 6423 splits, all of them needless). A wall (n_z = 0) takes
      // no error from the map: not probed.
      const double len = (m.vertices[b] - m.vertices[a]).norm();
      if (!split_it[e] && len > kLongEdge && im[e] != pm.z() && flat[e] > 1e-6f)
        split_it[e] = strays(field, m.vertices[a], m.vertices[b], image[a], image[b],
                             params.tolerance / flat[e]);
    });
    // Refused before the round is built when it would leave too many faces (a face with n
    // edges split becomes n + 1): Benchy's shell built its 900 000th face for nothing.
    std::size_t next_faces = 0;
    for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
      ++next_faces;
      for (std::size_t k = 0; k < 3; ++k) {
        const int edge = round_e.corner_edge[3 * fi + k];
        next_faces += edge >= 0 && split_it[static_cast<std::size_t>(edge)];
      }
    }
    if (params.max_faces > 0 && next_faces > params.max_faces) return too_many(params.max_faces);
    std::vector<int> mid(edges.size(), -1);  // each edge's midpoint vertex (-1: kept whole)
    const auto split = static_cast<std::size_t>(std::count(split_it.begin(), split_it.end(), 1));
    m.vertices.reserve(m.vertices.size() + split);
    image.reserve(image.size() + split);
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (!split_it[e]) continue;
      const auto [a, b] = edges[e];
      mid[e] = static_cast<int>(m.vertices.size());
      m.vertices.push_back(0.5 * (m.vertices[a] + m.vertices[b]));
      image.push_back(im[e]);
    }
    std::vector<std::array<int, 3>> faces;
    std::vector<char> final_next, settled_next;
    faces.reserve(next_faces);
    final_next.reserve(next_faces);
    settled_next.reserve(3 * next_faces);
    // A child face's corner is settled when it runs along a parent's edge kept whole.
    auto add = [&](std::array<int, 3> f, bool s0, bool s1, bool s2) {
      faces.push_back(f);
      settled_next.insert(settled_next.end(), {char(s0), char(s1), char(s2)});
    };
    for (std::size_t fi = 0; fi < m.faces.size(); ++fi) {
      const auto& f = m.faces[fi];
      int e[3] = {-1, -1, -1};
      int n = 0;
      if (!final_face[fi])
        for (int k = 0; k < 3; ++k) {
          const int edge = round_e.corner_edge[3 * fi + static_cast<std::size_t>(k)];
          n += (e[k] = edge < 0 ? -1 : mid[static_cast<std::size_t>(edge)]) >= 0;
        }
      if (n == 0) {
        add(f, true, true, true);  // final: its corners are never looked at again
      } else if (n == 1) {
        const int k = e[0] >= 0 ? 0 : e[1] >= 0 ? 1 : 2;  // split edge f[k] → f[k+1]
        const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3], mab = e[k];
        add({a, mab, c}, false, false, true);
        add({mab, b, c}, false, true, false);
      } else if (n == 2) {
        const int u = e[0] < 0 ? 0 : e[1] < 0 ? 1 : 2;  // the edge that stays whole: a → b
        const int a = f[u], b = f[(u + 1) % 3], c = f[(u + 2) % 3];
        const int mbc = e[(u + 1) % 3], mca = e[(u + 2) % 3];
        add({a, b, mbc}, true, false, false);
        add({a, mbc, mca}, false, false, false);
        add({mca, mbc, c}, false, false, false);
      } else {
        const int a = f[0], b = f[1], c = f[2], mab = e[0], mbc = e[1], mca = e[2];
        add({a, mab, mca}, false, false, false);
        add({mab, b, mbc}, false, false, false);
        add({mca, mbc, c}, false, false, false);
        add({mab, mbc, mca}, false, false, false);
      }
      final_next.resize(faces.size(), n == 0);
    }
    m.faces = std::move(faces);
    final_face = std::move(final_next);
    settled = std::move(settled_next);
    out.rounds = round + 1;
    out.edges_split += split;
    ctx.progress("normalize", std::min(1.0, 0.1 * (round + 1)));
    if (split == 0) break;
  }
  for (std::size_t v = 0; v < m.vertices.size(); ++v) m.vertices[v].z() = image[v];
  out.mesh = std::move(m);
  return out;
}

}  // namespace nonplanar
