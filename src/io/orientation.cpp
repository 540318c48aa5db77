#include <algorithm>
#include <vector>

#include "io/repair.hpp"

namespace nonplanar::io {
namespace {

void flip(std::array<int, 3>& f) {
  std::swap(f[1], f[2]);
}

}  // namespace

std::size_t orient_outward(TriangleMesh& mesh, const MeshTopology& topo, bool* inverted) {
  const std::size_t nf = mesh.faces.size();
  // Breadth-first over manifold edges: a neighbour that runs the shared edge in the same
  // direction has the opposite winding, so its flip state is the opposite of ours.
  std::vector<int> comp(nf, -1);
  std::vector<char> flipped(nf, 0);
  std::vector<int> queue;
  int ncomp = 0;
  for (std::size_t seed = 0; seed < nf; ++seed) {
    if (comp[seed] >= 0) continue;
    comp[seed] = ncomp;
    queue.assign(1, static_cast<int>(seed));
    for (std::size_t qi = 0; qi < queue.size(); ++qi) {
      const int f = queue[qi];
      for (int k = 0; k < 3; ++k) {
        const std::size_t c = 3 * static_cast<std::size_t>(f) + k;
        const int g = topo.across[c];
        if (g < 0 || comp[g] >= 0) continue;
        comp[g] = ncomp;
        flipped[g] = static_cast<char>(flipped[f] ^ topo.same_direction[c]);
        queue.push_back(g);
      }
    }
    ++ncomp;
  }
  for (std::size_t f = 0; f < nf; ++f)
    if (flipped[f]) flip(mesh.faces[f]);

  // Signed volume and bounding box per component, about the component's own first vertex so
  // that open pieces are judged independently of where the part sits.
  std::vector<double> vol(ncomp, 0.0);
  std::vector<Vec3> origin(ncomp, Vec3::Zero());
  std::vector<char> has_origin(ncomp, 0);
  std::vector<BoundingBox> box(ncomp);
  for (std::size_t f = 0; f < nf; ++f) {
    const int c = comp[f];
    const auto& t = mesh.faces[f];
    if (!has_origin[c]) origin[c] = mesh.vertices[t[0]], has_origin[c] = 1;
    const Vec3 a = mesh.vertices[t[0]] - origin[c];
    const Vec3 b = mesh.vertices[t[1]] - origin[c];
    const Vec3 d = mesh.vertices[t[2]] - origin[c];
    vol[c] += a.dot(b.cross(d)) / 6.0;
    for (int k = 0; k < 3; ++k) box[c].extend(mesh.vertices[t[k]]);
  }
  // An open piece's volume about any one point says nothing of its winding (a correctly wound
  // teapot lid read as inside out about its knob's tip). Close each open piece with a fan of
  // triangles from its boundary's centroid over every open edge, and judge the closed volume.
  std::vector<Vec3> rim_sum(ncomp, Vec3::Zero());
  std::vector<std::size_t> rim_count(ncomp, 0);
  auto for_each_open_edge = [&](auto&& f) {  // f(component, from, to): the edge as wound now
    for (std::size_t face = 0; face < nf; ++face)
      for (int k = 0; k < 3; ++k) {
        if (topo.across[3 * face + k] != MeshTopology::kOpen) continue;
        auto t = mesh.faces[face];
        if (flipped[face]) flip(t);  // back to the corner order the topology counts in
        int from = t[k], to = t[(k + 1) % 3];
        if (flipped[face]) std::swap(from, to);
        f(comp[face], mesh.vertices[from], mesh.vertices[to]);
      }
  };
  for_each_open_edge(
      [&](int c, const Vec3& from, const Vec3&) { rim_sum[c] += from, ++rim_count[c]; });
  for_each_open_edge([&](int c, const Vec3& from, const Vec3& to) {
    const Vec3 centre = rim_sum[c] / static_cast<double>(rim_count[c]) - origin[c];
    vol[c] += centre.dot((to - origin[c]).cross(from - origin[c])) / 6.0;
  });
  auto inside = [&](int a, int b) {  // bbox of a strictly inside bbox of b
    return (box[a].min.array() > box[b].min.array()).all() &&
           (box[a].max.array() < box[b].max.array()).all();
  };
  std::vector<char> flip_comp(ncomp, 0);
  for (int c = 0; c < ncomp; ++c) {
    if (vol[c] >= 0) continue;
    bool cavity = false;
    for (int o = 0; o < ncomp && !cavity; ++o) cavity = o != c && vol[o] > 0 && inside(c, o);
    if (!cavity) flip_comp[c] = 1;
  }
  std::size_t changed = 0;
  std::vector<std::size_t> comp_faces(ncomp, 0), comp_changed(ncomp, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (flip_comp[comp[f]]) flip(mesh.faces[f]);
    const bool net = flipped[f] != flip_comp[comp[f]];  // net change of this face's winding
    changed += net;
    comp_changed[comp[f]] += net;
    ++comp_faces[comp[f]];
  }
  // "Inside out" when most of a piece had to be reversed, wherever the search started.
  bool any_inverted = false;
  for (int c = 0; c < ncomp; ++c) any_inverted |= 2 * comp_changed[c] > comp_faces[c];
  if (inverted) *inverted = any_inverted;
  return changed;
}

}  // namespace nonplanar::io
