// Small helpers for tests that write files.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "nonplanar/io.hpp"

namespace nonplanar::test {

inline void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

inline std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// ASCII STL text of a mesh, with the given line ending and deliberately wrong normals.
inline std::string ascii_stl(const TriangleMesh& m, const std::string& eol) {
  std::ostringstream s;
  s.precision(17);
  s << "solid test" << eol;
  for (const auto& f : m.faces) {
    s << " facet normal 0 0 -1" << eol << "  outer loop" << eol;
    for (int v : f) {
      const Vec3& p = m.vertices[v];
      s << "   vertex " << p.x() << ' ' << p.y() << ' ' << p.z() << eol;
    }
    s << "  endloop" << eol << " endfacet" << eol;
  }
  s << "endsolid test" << eol;
  return s.str();
}

/// Loader parameters that keep the file's own coordinates.
inline LoadParams unplaced() {
  LoadParams p;
  p.place_on_bed = false;
  return p;
}

}  // namespace nonplanar::test
