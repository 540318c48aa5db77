#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "io/repair.hpp"

namespace nonplanar::io {
namespace {

std::uint64_t mix(std::uint64_t h) {  // splitmix64 finaliser
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

std::uint64_t hash_point(const Vec3& p) {
  std::uint64_t b[3];
  for (int k = 0; k < 3; ++k) {
    const double v = p[k] == 0.0 ? 0.0 : p[k];  // +0 and -0 are the same point
    std::memcpy(&b[k], &v, 8);
  }
  return mix(b[0] ^ mix(b[1] ^ mix(b[2])));
}

std::uint64_t hash_cell(std::int64_t x, std::int64_t y, std::int64_t z) {
  return mix(static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^
             mix(static_cast<std::uint64_t>(y) ^ mix(static_cast<std::uint64_t>(z))));
}

// Open-addressing table of int values keyed by a 64-bit hash; the caller resolves collisions
// by comparing the stored value's data.
class IndexTable {
 public:
  explicit IndexTable(std::size_t n) {
    std::size_t cap = 16;
    while (cap < 2 * n) cap <<= 1;
    slots_.assign(cap, -1);
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

TriangleMesh weld(const TriangleMesh& raw, double tolerance, std::size_t* collapsed) {
  const std::size_t n = raw.vertices.size();
  // Pass 1: exact duplicates (an STL repeats each shared vertex bit for bit).
  std::vector<int> exact(n);
  std::vector<int> unique;  // raw index of each unique point
  unique.reserve(n / 4 + 16);
  {
    IndexTable table(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& p = raw.vertices[i];
      const std::size_t s = table.probe(hash_point(p), [&](int u) {
        return raw.vertices[unique[u]] == p;
      });
      if (table.slot(s) < 0) {
        table.slot(s) = static_cast<int>(unique.size());
        unique.push_back(static_cast<int>(i));
      }
      exact[i] = table.slot(s);
    }
  }
  // Pass 2: tolerant merge of unique points on a grid of cell 2·tol. A point within tol of
  // another lies in the same cell or the one next to it on the side nearer the point, so
  // 8 cells are searched.
  std::vector<int> to_out(unique.size());
  TriangleMesh out;
  out.vertices.reserve(unique.size());
  if (tolerance > 0) {
    const double cell = 2.0 * tolerance, tol2 = tolerance * tolerance;
    IndexTable table(unique.size());
    std::vector<int> next;  // chain of output vertices in the same cell
    std::vector<std::int64_t> cell_of;  // 3 per output vertex
    for (std::size_t u = 0; u < unique.size(); ++u) {
      const Vec3& p = raw.vertices[unique[u]];
      std::int64_t c[3], side[3];
      for (int k = 0; k < 3; ++k) {
        const double f = p[k] / cell;
        c[k] = static_cast<std::int64_t>(std::floor(f));
        side[k] = (f - static_cast<double>(c[k])) < 0.5 ? -1 : 1;
      }
      int found = -1;
      for (int m = 0; m < 8 && found < 0; ++m) {
        const std::int64_t q[3] = {c[0] + ((m & 1) ? side[0] : 0), c[1] + ((m & 2) ? side[1] : 0),
                                   c[2] + ((m & 4) ? side[2] : 0)};
        const std::size_t s = table.probe(hash_cell(q[0], q[1], q[2]), [&](int o) {
          return cell_of[3 * o] == q[0] && cell_of[3 * o + 1] == q[1] && cell_of[3 * o + 2] == q[2];
        });
        for (int o = table.slot(s); o >= 0 && found < 0; o = next[o])
          if ((out.vertices[o] - p).squaredNorm() <= tol2) found = o;
      }
      if (found < 0) {
        found = static_cast<int>(out.vertices.size());
        out.vertices.push_back(p);
        cell_of.insert(cell_of.end(), {c[0], c[1], c[2]});
        const std::size_t s = table.probe(hash_cell(c[0], c[1], c[2]), [&](int o) {
          return cell_of[3 * o] == c[0] && cell_of[3 * o + 1] == c[1] && cell_of[3 * o + 2] == c[2];
        });
        next.push_back(table.slot(s));  // prepend to the cell's chain
        table.slot(s) = found;
      }
      to_out[u] = found;
    }
  } else {
    for (std::size_t u = 0; u < unique.size(); ++u) {
      to_out[u] = static_cast<int>(u);
      out.vertices.push_back(raw.vertices[unique[u]]);
    }
  }

  std::size_t dropped = 0;
  out.faces.reserve(raw.faces.size());
  std::vector<char> used(out.vertices.size(), 0);
  for (const auto& f : raw.faces) {
    const std::array<int, 3> g = {to_out[exact[f[0]]], to_out[exact[f[1]]], to_out[exact[f[2]]]};
    if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) {
      ++dropped;
      continue;
    }
    used[g[0]] = used[g[1]] = used[g[2]] = 1;
    out.faces.push_back(g);
  }
  if (collapsed) *collapsed = dropped;
  // Drop vertices no face uses (OBJ/OFF may list extras; collapsed faces leave some).
  std::vector<int> remap(out.vertices.size(), -1);
  std::size_t m = 0;
  for (std::size_t i = 0; i < out.vertices.size(); ++i)
    if (used[i]) {
      remap[i] = static_cast<int>(m);
      out.vertices[m++] = out.vertices[i];
    }
  out.vertices.resize(m);
  for (auto& f : out.faces)
    for (int& v : f) v = remap[v];
  return out;
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
