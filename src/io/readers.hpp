// The mesh parsers. Each takes a file's bytes and returns an unwelded triangle mesh, or an
// Error whose message names the line or record (the loader prefixes the file name).
#pragma once

#include <string_view>

#include "nonplanar/io.hpp"

namespace nonplanar::io {

/// STL, binary or ASCII. Binary is recognised by its size (84 + 50·n bytes), not by a
/// "solid" prefix, which some binary exporters write into the header. *format is set.
Expected<TriangleMesh> parse_stl(std::string_view data, MeshFormat* format);

/// Wavefront OBJ: v and f records (v, v/vt, v//vn, v/vt/vn; negative indices), polygons
/// fan-triangulated; other records ignored.
Expected<TriangleMesh> parse_obj(std::string_view data);

/// OFF (also COFF/NOFF headers): extra per-vertex or per-face values are ignored.
Expected<TriangleMesh> parse_off(std::string_view data);

/// 3MF through lib3mf: every build item, components resolved, transforms applied, in mm
/// whatever the model's `unit` (micron … meter). Triangles are counted before any is built:
/// more than `max_triangles` is an invalid_mesh error. A non-finite transform is an error.
/// `objects` (optional) gets each build item's object (its name: the model's, PrusaSlicer's or
/// OrcaSlicer's config's, or "object K" for item K from 1; instances of one object share an
/// id) and the faces each item added.
Expected<TriangleMesh> parse_3mf(std::string_view data, std::size_t max_triangles = 50'000'000,
                                 PlateObjects* objects = nullptr);

}  // namespace nonplanar::io
