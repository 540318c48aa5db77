#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/huge_pages.hpp"
#include "io/hash_mix.hpp"
#include "io/mesh_buffer.hpp"
#include "io/readers.hpp"

namespace nonplanar::io {
namespace {

constexpr std::size_t kHeader = 84;  // 80-byte header + uint32 triangle count
constexpr std::size_t kRecord = 50;  // normal, 3 vertices (12 floats) + uint16 attribute

bool starts_with_solid(std::string_view data) {
  std::size_t i = 0;
  while (i < data.size() &&
         (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n'))
    ++i;
  return data.substr(i, 5) == "solid";
}

// Exact-duplicate index of float triples, growing as needed. A binary STL repeats every
// shared vertex bit for bit, so merging them while parsing keeps ~1/6 of the corners and
// never materialises the triangle soup. The points are kept as the mesh's own doubles (a float
// converts exactly, and compares equal exactly when its bits do: no NaN, -0 folded), so
// they need no copy of their own.
class FloatPointIndex {
 public:
  explicit FloatPointIndex(std::size_t expected) {
    reserve_huge(points_, expected);
    rehash(expected);
  }
  int insert(const float* p) {
    if (2 * (points_.size() + 1) > slots_.size()) rehash(2 * slots_.size());
    const Vec3 v(p[0], p[1], p[2]);
    for (std::size_t i = hash(p) & mask_;; i = (i + 1) & mask_) {
      const int s = slots_[i];
      if (s < 0) {
        slots_[i] = static_cast<int>(points_.size());
        points_.push_back(v);
        return slots_[i];
      }
      if (points_[s] == v) return s;
    }
  }
  std::vector<Vec3> take_points() { return std::move(points_); }

 private:
  // The x and y bits, then z's, mixed: a product alone left the low bits zero on meshes
  // made on a grid and took 16 probes an insert on the sine roof (32 on the terrain tile).
  static std::size_t hash(const float* p) {
    std::uint32_t b[3];
    std::memcpy(b, p, 12);
    return static_cast<std::size_t>(mix64((std::uint64_t{b[0]} << 32 | b[1]) ^ mix64(b[2])));
  }
  void rehash(std::size_t n) {
    std::size_t cap = 64;
    while (cap < 2 * n) cap <<= 1;
    assign_huge(slots_, cap, -1);
    mask_ = cap - 1;
    for (std::size_t s = 0; s < points_.size(); ++s) {
      const float f[3] = {static_cast<float>(points_[s].x()), static_cast<float>(points_[s].y()),
                          static_cast<float>(points_[s].z())};
      std::size_t i = hash(f) & mask_;
      while (slots_[i] >= 0) i = (i + 1) & mask_;
      slots_[i] = static_cast<int>(s);
    }
  }
  std::vector<int> slots_;
  std::size_t mask_ = 0;
  std::vector<Vec3> points_;
};

Expected<TriangleMesh> parse_binary(std::string_view data, std::uint32_t count) {
  TriangleMesh mesh;
  reserve_huge(mesh.faces, count);
  mesh.faces.resize(count);
  FloatPointIndex index(count / 2 + 16);  // a closed mesh has about half as many vertices
  const char* p = data.data() + kHeader;
  for (std::uint32_t t = 0; t < count; ++t, p += kRecord) {
    float f[9];
    std::memcpy(f, p + 12, sizeof f);  // skip the stored normal: it is often zero or wrong
    for (int k = 0; k < 9; ++k)
      if (!std::isfinite(f[k]))
        return Error{Status::parse_error,
                     "triangle " + std::to_string(t + 1) + ": coordinate is not a finite number"};
    for (int k = 0; k < 3; ++k) {
      if (f[3 * k] == 0.0f) f[3 * k] = 0.0f;  // fold -0 into +0 so the bits compare equal
      if (f[3 * k + 1] == 0.0f) f[3 * k + 1] = 0.0f;
      if (f[3 * k + 2] == 0.0f) f[3 * k + 2] = 0.0f;
      mesh.faces[t][k] = index.insert(f + 3 * k);
    }
  }
  mesh.vertices = index.take_points();
  return mesh;
}

Expected<TriangleMesh> parse_ascii(std::string_view data) {
  TriangleMesh mesh;
  Tokenizer tok(data);
  int in_facet = 0;  // vertices read in the current facet
  bool saw_solid = false;
  while (!tok.at_end()) {
    const std::string_view t = tok.next();
    const int line = tok.line();
    if (t == "solid") {
      saw_solid = true;
      tok.rest_of_line();  // the solid's name may contain anything
    } else if (t == "vertex") {
      Vec3 v;
      for (int k = 0; k < 3; ++k) {
        const std::string_view num = tok.next();
        const auto d = parse_double(num);
        if (!d) {
          if (num.empty()) return parse_error_at(tok.line(), "file ends inside a vertex");
          return parse_error_at(tok.line(), "vertex coordinate '" + std::string(num.substr(0, 40)) +
                                                "' is not a finite number");
        }
        v[k] = *d;
      }
      mesh.vertices.push_back(v);
      if (++in_facet > 3) return parse_error_at(line, "facet has more than 3 vertices");
    } else if (t == "endloop" || t == "endfacet") {
      if (t == "endloop") {
        if (in_facet != 3) return parse_error_at(line, "facet does not have 3 vertices");
        const int b = static_cast<int>(mesh.vertices.size()) - 3;
        mesh.faces.push_back({b, b + 1, b + 2});
        in_facet = 0;
      }
    } else if (t == "facet" || t == "normal" || t == "outer" || t == "loop") {
      if (t == "normal") tok.rest_of_line();  // stored normals are ignored, even malformed ones
    } else if (t == "endsolid") {
      tok.rest_of_line();
    } else {
      return parse_error_at(line, "unexpected '" + std::string(t.substr(0, 40)) + "' in ASCII STL");
    }
  }
  if (!saw_solid) return parse_error_at(1, "not an STL file");
  if (in_facet != 0) return parse_error_at(tok.line(), "file ends inside a facet");
  return mesh;
}

}  // namespace

Expected<TriangleMesh> parse_stl(std::string_view data, MeshFormat* format) {
  if (data.empty()) return Error{Status::parse_error, "file is empty"};
  if (data.size() >= kHeader) {
    std::uint32_t count = 0;
    std::memcpy(&count, data.data() + 80, 4);
    if (data.size() == kHeader + kRecord * static_cast<std::size_t>(count)) {
      if (format) *format = MeshFormat::stl_binary;
      if (count == 0) return Error{Status::invalid_mesh, "binary STL holds no triangles"};
      return parse_binary(data, count);
    }
    if (!starts_with_solid(data))
      return Error{Status::parse_error,
                   "truncated or padded binary STL: header says " + std::to_string(count) +
                       " triangles (" + std::to_string(kHeader + kRecord * std::size_t{count}) +
                       " bytes) but the file has " + std::to_string(data.size()) + " bytes"};
  } else if (!starts_with_solid(data)) {
    return Error{Status::parse_error, "file too short for a binary STL (" +
                                          std::to_string(data.size()) + " bytes) and not ASCII"};
  }
  if (format) *format = MeshFormat::stl_ascii;
  return parse_ascii(data);
}

}  // namespace nonplanar::io
