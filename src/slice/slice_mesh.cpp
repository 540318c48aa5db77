// Planar slicing: triangle–plane segments chained through the mesh's edges into loops.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "core/parallel.hpp"
#include "core/polygon_ops.hpp"
#include "nonplanar/slice.hpp"

namespace nonplanar {
namespace {

std::uint64_t edge_key(int a, int b) {
  const auto [lo, hi] = std::minmax(a, b);
  return (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi);
}

struct Segment {
  std::uint64_t from, to;  // the mesh edges the segment starts and ends on
  Vec2 p, q;
};

// Where the plane z = h cuts edge (a, b), computed from the lower-index end so both faces
// of the edge get the same bits.
Vec2 cut(const TriangleMesh& m, int a, int b, double h) {
  if (a > b) std::swap(a, b);
  const Vec3& A = m.vertices[a];
  const Vec3& B = m.vertices[b];
  const double t = (h - A.z()) / (B.z() - A.z());
  return (A + t * (B - A)).head<2>();
}

std::vector<Polygon> layer_loops(const TriangleMesh& m, const std::vector<int>& candidates,
                                 double h) {
  std::vector<Segment> segs;
  for (int f : candidates) {
    const auto& t = m.faces[f];
    // A vertex exactly on the plane counts as above: every edge then crosses cleanly.
    bool above[3];
    for (int k = 0; k < 3; ++k) above[k] = m.vertices[t[k]].z() >= h;
    if (above[0] == above[1] && above[1] == above[2]) continue;
    int e[2], n = 0;
    for (int k = 0; k < 3 && n < 2; ++k)
      if (above[k] != above[(k + 1) % 3]) e[n++] = k;
    Segment s;
    s.from = edge_key(t[e[0]], t[(e[0] + 1) % 3]);
    s.to = edge_key(t[e[1]], t[(e[1] + 1) % 3]);
    s.p = cut(m, t[e[0]], t[(e[0] + 1) % 3], h);
    s.q = cut(m, t[e[1]], t[(e[1] + 1) % 3], h);
    // Material on the left (outward normal on the right): counter-clockwise outlines.
    const Vec3 nrm =
        (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    const Vec2 d = s.q - s.p;
    if (nrm.x() * d.y() - nrm.y() * d.x() < 0) {
      std::swap(s.p, s.q);
      std::swap(s.from, s.to);
    }
    segs.push_back(s);
  }
  std::unordered_map<std::uint64_t, int> starting;
  starting.reserve(segs.size() * 2);
  for (std::size_t i = 0; i < segs.size(); ++i) starting.emplace(segs[i].from, static_cast<int>(i));
  std::vector<char> used(segs.size(), 0);
  std::vector<Polygon> loops;
  std::vector<Polygon> open;
  for (std::size_t s0 = 0; s0 < segs.size(); ++s0) {
    if (used[s0]) continue;
    Polygon loop;
    int cur = static_cast<int>(s0);
    bool closed = false;
    int last = cur;
    while (cur >= 0 && !used[cur]) {
      used[cur] = 1;
      last = cur;
      loop.push_back(segs[cur].p);
      const auto it = starting.find(segs[cur].to);
      if (it == starting.end()) break;
      if (it->second == static_cast<int>(s0)) closed = true;
      cur = it->second;
    }
    // An open fragment ends where its last segment ends, so fragments that continue one
    // another meet exactly and are joined below.
    if (!closed) loop.push_back(segs[last].q);
    if (closed)
      loops.push_back(std::move(loop));
    else if (loop.size() >= 2)
      open.push_back(std::move(loop));
  }
  // Holes in the mesh leave open chains: join chains whose ends are within 1 mm, greedily,
  // and close a chain whose own ends meet.
  const double gap = 1.0;
  while (!open.empty()) {
    Polygon chain = std::move(open.back());
    open.pop_back();
    for (bool grew = true; grew;) {
      grew = false;
      // Join the nearest chain that continues this one; close on itself only when no other
      // chain is nearer (a chain starting just past the gap would otherwise close into a
      // sliver).
      double best = std::min(gap, (chain.back() - chain.front()).norm());
      std::size_t bi = open.size();
      for (std::size_t i = 0; i < open.size(); ++i) {
        const double d = (open[i].front() - chain.back()).norm();
        if (d < best) best = d, bi = i;
      }
      if (bi < open.size()) {
        chain.insert(chain.end(), open[bi].begin(), open[bi].end());
        open.erase(open.begin() + static_cast<long>(bi));
        grew = true;
      }
    }
    if (chain.size() >= 3 && (chain.back() - chain.front()).norm() < gap)
      loops.push_back(std::move(chain));
  }
  return loops;
}

}  // namespace

Expected<std::vector<SlicedLayer>> slice_mesh(const TriangleMesh& mesh, const SliceParams& p,
                                              const Context& ctx) {
  ctx.progress("slice", 0);
  if (!(p.layer_height > 0) || !(p.first_layer_height > 0) || !std::isfinite(p.layer_height) ||
      !std::isfinite(p.first_layer_height))
    return Error{Status::invalid_argument, "layer_height: must be a finite number > 0"};
  const BoundingBox box = bounding_box(mesh);
  if (box.empty()) return Error{Status::invalid_mesh, "slice: empty mesh"};
  std::vector<SlicedLayer> layers;
  for (double z0 = box.min.z(), h = p.first_layer_height; z0 < box.max.z() - 1e-9;
       z0 += h, h = p.layer_height) {
    // As PrusaSlicer: a layer exists only while its mid-plane is inside the part, so the
    // last layer never overshoots the top by more than half a layer.
    if (z0 + 0.5 * h >= box.max.z() && !layers.empty()) break;
    SlicedLayer l;
    l.z_bottom = z0;
    l.z_top = z0 + h;
    l.z_slice = std::min(z0 + 0.5 * h, box.max.z() - 1e-6);
    layers.push_back(l);
    if (layers.size() > 200000)
      return Error{Status::invalid_argument,
                   "slice: more than 200000 layers (layer_height too small?)"};
  }
  return slice_mesh_at(mesh, std::move(layers), ctx);
}

Expected<std::vector<SlicedLayer>> slice_mesh_at(const TriangleMesh& mesh,
                                                 std::vector<SlicedLayer> layers,
                                                 const Context& ctx) {
  // Faces sorted by their lowest z; a layer only looks at faces that can reach it.
  const std::size_t nf = mesh.faces.size();
  std::vector<int> order(nf);
  std::vector<double> lo(nf), hi(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    order[f] = static_cast<int>(f);
    lo[f] = hi[f] = mesh.vertices[mesh.faces[f][0]].z();
    for (int k = 1; k < 3; ++k) {
      lo[f] = std::min(lo[f], mesh.vertices[mesh.faces[f][k]].z());
      hi[f] = std::max(hi[f], mesh.vertices[mesh.faces[f][k]].z());
    }
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lo[a] < lo[b]; });
  std::vector<double> sorted_lo(nf);
  for (std::size_t i = 0; i < nf; ++i) sorted_lo[i] = lo[order[i]];
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> done{0};
  core::parallel_for(std::size_t{0}, layers.size(), [&](std::size_t i) {
    if (stop || ctx.cancelled()) return stop = true, void();
    const double h = layers[i].z_slice;
    std::vector<int> cand;
    const auto end = std::upper_bound(sorted_lo.begin(), sorted_lo.end(), h) - sorted_lo.begin();
    for (long k = 0; k < end; ++k)
      if (hi[order[k]] >= h) cand.push_back(order[k]);
    layers[i].islands = clip::simplify(clip::union_loops(layer_loops(mesh, cand, h)), 0.005);
    ++done;
  });
  if (stop) return Error{Status::cancelled, "cancelled"};
  ctx.progress("slice", 1.0);
  return layers;
}

}  // namespace nonplanar
