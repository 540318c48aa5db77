// Small helpers for tests that write files.
#pragma once

#include <cstdlib>
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

/// The relationship of a 3MF package's root to its model, /3D/3dmodel.model.
inline const char* kModelRelationship =
    "<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel-1\" Type=\"http://schemas.microsoft."
    "com/3dmanufacturing/2013/01/3dmodel\"/>";

/// A 3MF package zipped by `zip` (deflated entries) from its root relationships (the
/// <Relationship> elements) and its model XML, written as dir/name; false when `zip` fails.
inline bool zip_3mf(const std::filesystem::path& dir, const std::string& name,
                    const std::string& relationships, const std::string& model) {
  const std::filesystem::path pkg = dir / (name + ".parts");
  std::filesystem::create_directories(pkg / "_rels");
  std::filesystem::create_directories(pkg / "3D");
  write_bytes(pkg / "[Content_Types].xml",
              "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Types xmlns=\"http://schemas."
              "openxmlformats.org/package/2006/content-types\"><Default Extension=\"rels\" "
              "ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>"
              "<Default Extension=\"model\" ContentType=\"application/vnd.ms-package."
              "3dmanufacturing-3dmodel+xml\"/><Default Extension=\"png\" "
              "ContentType=\"image/png\"/></Types>");
  write_bytes(pkg / "_rels" / ".rels",
              "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Relationships xmlns=\"http://"
              "schemas.openxmlformats.org/package/2006/relationships\">" +
                  relationships + "</Relationships>");
  write_bytes(pkg / "3D" / "3dmodel.model", model);
  const std::string cmd = "cd '" + pkg.string() + "' && zip -q -X -r '" + (dir / name).string() +
                          "' '[Content_Types].xml' _rels 3D";
  return std::system(cmd.c_str()) == 0;
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
