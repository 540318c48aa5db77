#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "core/huge_pages.hpp"
#include "io/hash_mix.hpp"
#include "io/repair.hpp"

namespace nonplanar::io {
namespace {

std::uint64_t hash_point(const Vec3& p) {
  std::uint64_t b[3];
  for (int k = 0; k < 3; ++k) {
    const double v = p[k] == 0.0 ? 0.0 : p[k];  // +0 and -0 are the same point
    std::memcpy(&b[k], &v, 8);
  }
  return mix64(b[0] ^ mix64(b[1] ^ mix64(b[2])));
}

std::uint64_t hash_cell(std::int64_t x, std::int64_t y, std::int64_t z) {
  return mix64(static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^
               mix64(static_cast<std::uint64_t>(y) ^ mix64(static_cast<std::uint64_t>(z))));
}

// Open-addressing table of int values keyed by a 64-bit hash; the caller resolves collisions
// by comparing the stored value's data.
class IndexTable {
 public:
  explicit IndexTable(std::size_t n) {
    std::size_t cap = 16;
    while (cap < 2 * n) cap <<= 1;
    assign_huge(slots_, cap, -1);
    mask_ = cap - 1;
  }
  // Visits slots starting at hash until visit() returns true (found) or an empty slot is
  // reached; returns the empty slot index (or found slot).
  template <class Visit>
  std::size_t probe(std::uint64_t h, Visit visit) const {
    for (std::size_t i = h & mask_;; i = (i + 1) & mask_) {
      if (slots_[i] < 0 || visit(slots_[i])) return i;
    }
  }
  int& slot(std::size_t i) { return slots_[i]; }

 private:
  std::vector<int> slots_;
  std::size_t mask_ = 0;
};

}  // namespace

TriangleMesh weld(TriangleMesh mesh, double tolerance, std::size_t* collapsed,
                  std::vector<int>* tags) {
  const bool tagged = tags && tags->size() == mesh.faces.size();
  std::vector<Vec3>& pts = mesh.vertices;
  const std::size_t n = pts.size();
  // Pass 1: exact duplicates (an STL repeats each shared vertex bit for bit; the binary
  // reader has merged those already). Unique points are compacted to the front in place.
  std::vector<int> map;
  assign_huge(map, n, 0);
  std::size_t nu = 0;
  {
    IndexTable table(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 p = pts[i];
      const std::size_t s = table.probe(hash_point(p), [&](int u) { return pts[u] == p; });
      if (table.slot(s) < 0) {
        table.slot(s) = static_cast<int>(nu);
        pts[nu++] = p;
      }
      map[i] = table.slot(s);
    }
  }
  // Pass 2: tolerant merge of unique points on a grid of cell 64·tol. A point within tol of
  // another lies in the same cell, or in the neighbour across a face it is within tol of;
  // so most points search one cell, and at most 8. Output points are compacted in place too
  // (output index <= unique index, so nothing is overwritten before it is read).
  std::vector<int> to_out;
  assign_huge(to_out, nu, 0);
  std::size_t no = 0;
  if (tolerance > 0) {
    const double cell = 64.0 * tolerance, tol2 = tolerance * tolerance;
    const double near = tolerance / cell;  // a fraction of the cell
    auto cell_of = [&](const Vec3& p, int k) {
      return static_cast<std::int64_t>(std::floor(p[k] / cell));
    };
    IndexTable table(nu);
    std::vector<int> next;  // chain of output points in the same cell
    reserve_huge(next, nu);
    for (std::size_t u = 0; u < nu; ++u) {
      const Vec3 p = pts[u];
      std::int64_t c[3], side[3];
      for (int k = 0; k < 3; ++k) {
        const double f = p[k] / cell;
        c[k] = static_cast<std::int64_t>(std::floor(f));
        const double frac = f - static_cast<double>(c[k]);
        side[k] = frac <= near ? -1 : frac >= 1.0 - near ? 1 : 0;
      }
      auto probe_cell = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
        return table.probe(hash_cell(x, y, z), [&](int o) {
          return cell_of(pts[o], 0) == x && cell_of(pts[o], 1) == y && cell_of(pts[o], 2) == z;
        });
      };
      int found = -1;
      for (int m = 0; m < 8 && found < 0; ++m) {
        if (((m & 1) && !side[0]) || ((m & 2) && !side[1]) || ((m & 4) && !side[2])) continue;
        const std::size_t s =
            probe_cell(c[0] + ((m & 1) ? side[0] : 0), c[1] + ((m & 2) ? side[1] : 0),
                       c[2] + ((m & 4) ? side[2] : 0));
        for (int o = table.slot(s); o >= 0 && found < 0; o = next[o])
          if ((pts[o] - p).squaredNorm() <= tol2) found = o;
      }
      if (found < 0) {
        found = static_cast<int>(no);
        pts[no++] = p;
        const std::size_t s = probe_cell(c[0], c[1], c[2]);
        next.push_back(table.slot(s));  // prepend to the cell's chain
        table.slot(s) = found;
      }
      to_out[u] = found;
    }
  } else {
    for (std::size_t u = 0; u < nu; ++u) to_out[u] = static_cast<int>(u);
    no = nu;
  }

  // Remap faces in place, dropping those that lost a corner to the merge.
  std::size_t kept = 0;
  std::vector<char> used(no, 0);
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
    const auto& f = mesh.faces[i];
    const std::array<int, 3> g = {to_out[map[f[0]]], to_out[map[f[1]]], to_out[map[f[2]]]};
    if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) continue;
    used[g[0]] = used[g[1]] = used[g[2]] = 1;
    if (tagged) (*tags)[kept] = (*tags)[i];
    mesh.faces[kept++] = g;
  }
  if (collapsed) *collapsed = mesh.faces.size() - kept;
  mesh.faces.resize(kept);
  if (tagged) tags->resize(kept);
  // Drop points no face uses (OBJ/OFF may list extras; collapsed faces leave some).
  std::vector<int> remap(no, -1);
  std::size_t m = 0;
  for (std::size_t i = 0; i < no; ++i)
    if (used[i]) {
      remap[i] = static_cast<int>(m);
      pts[m++] = pts[i];
    }
  pts.resize(m);
  pts.shrink_to_fit();
  for (auto& f : mesh.faces)
    for (int& v : f) v = remap[v];
  return mesh;
}

double weld_tolerance(const TriangleMesh& raw, double rel) {
  if (rel <= 0) return 0.0;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  const std::size_t stride = std::max<std::size_t>(1, raw.faces.size() / 65536);
  // A sample of edge lengths, for the median; room made once (grown by doubling, its buffers
  // faulted in twice the memory, 185 page faults on the sine roof's 37 000 faces).
  std::vector<double> edges;
  edges.reserve(3 * ((raw.faces.size() + stride - 1) / stride));
  for (std::size_t i = 0; i < raw.faces.size(); ++i) {
    const auto& f = raw.faces[i];
    const Vec3 &a = raw.vertices[f[0]], &b = raw.vertices[f[1]], &c = raw.vertices[f[2]];
    if ((b - a).cross(c - a).squaredNorm() == 0.0) continue;  // no area: says nothing of size
    lo = lo.cwiseMin(a).cwiseMin(b).cwiseMin(c);
    hi = hi.cwiseMax(a).cwiseMax(b).cwiseMax(c);
    if (i % stride == 0)
      for (const auto& [p, q] : {std::pair{&a, &b}, std::pair{&b, &c}, std::pair{&c, &a}})
        edges.push_back((*q - *p).norm());
  }
  if (edges.empty()) return 0.0;
  auto mid = edges.begin() + static_cast<std::ptrdiff_t>(edges.size() / 2);
  std::nth_element(edges.begin(), mid, edges.end());
  return std::min(rel * (hi - lo).norm(), 1e-3 * *mid);
}

std::size_t remove_duplicate_faces(TriangleMesh& mesh, std::vector<int>* tags) {
  const bool tagged = tags && tags->size() == mesh.faces.size();
  // A face's key: its corners rotated to start at the smallest, so the winding is kept.
  auto key = [](std::array<int, 3> f) {
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    return f;
  };
  auto hash = [](const std::array<int, 3>& k) {
    return mix64(static_cast<std::uint64_t>(static_cast<std::uint32_t>(k[0])) ^
                 mix64(static_cast<std::uint64_t>(static_cast<std::uint32_t>(k[1])) << 32 ^
                       static_cast<std::uint32_t>(k[2])));
  };
  IndexTable table(mesh.faces.size());
  std::size_t kept = 0;
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
    const std::array<int, 3> k = key(mesh.faces[i]);
    const std::size_t s = table.probe(hash(k), [&](int o) { return key(mesh.faces[o]) == k; });
    if (table.slot(s) >= 0) continue;  // the same face, wound the same way, again
    mesh.faces[kept] = mesh.faces[i];
    if (tagged) (*tags)[kept] = (*tags)[i];
    table.slot(s) = static_cast<int>(kept++);
  }
  const std::size_t removed = mesh.faces.size() - kept;
  mesh.faces.resize(kept);
  if (tagged) tags->resize(kept);
  return removed;
}

std::size_t count_zero_area_faces(const TriangleMesh& mesh, double tolerance) {
  std::size_t n = 0;
  for (const auto& f : mesh.faces) {
    const Vec3& a = mesh.vertices[f[0]];
    const Vec3& b = mesh.vertices[f[1]];
    const Vec3& c = mesh.vertices[f[2]];
    const double twice_area = (b - a).cross(c - a).norm();
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (twice_area <= tolerance * longest) ++n;  // height = 2A / longest edge
  }
  return n;
}

}  // namespace nonplanar::io
