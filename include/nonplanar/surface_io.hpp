// Exchange format of fitted surfaces (docs/surface-format.md): JSON with degrees, knots,
// control points, weights and the (x, y) → (u, v) map, so any tool can evaluate them; and
// an OBJ tessellation for viewers.
#pragma once

#include <filesystem>
#include <vector>

#include "nonplanar/nurbs.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

/// One surface in a file: the patch it belongs to, the height field and its fit errors (mm).
struct SurfaceRecord {
  int patch = -1;
  HeightField surface;
  double rms_error = 0, max_error = 0;
  int layer = -1;              ///< for curved layers: 0 = top of the stack; −1: a fit
  bool has_footprint = false;  ///< the patch's XY box, written as "footprint"
  Vec2 footprint_min{0, 0}, footprint_max{0, 0};
};

/// Writes {"format": "nonplanar-surfaces", "version": 1, "units": "mm", "surfaces": [...]}.
/// Atomic.
Expected<void> write_surfaces_json(const std::filesystem::path& file,
                                   const std::vector<SurfaceRecord>& surfaces);

/// The same document as text (indent: as nlohmann::json::dump; -1 for one line), for a
/// caller that embeds it in a file of its own (the print plan, print_plan.hpp).
std::string surfaces_json(const std::vector<SurfaceRecord>& surfaces, int indent = -1);

/// Reads what write_surfaces_json wrote; every surface is checked with valid().
/// Errors: "FILE: what is wrong" (parse_error).
Expected<std::vector<SurfaceRecord>> read_surfaces_json(const std::filesystem::path& file);

/// Parses the JSON text itself (for tests and fuzzing); errors without the file name.
Expected<std::vector<SurfaceRecord>> parse_surfaces_json(std::string_view text);

/// Each surface tessellated over its footprint rectangle as a `resolution`² grid of quads
/// (two triangles each), one OBJ group per surface. Atomic.
Expected<void> write_surfaces_obj(const std::filesystem::path& file,
                                  const std::vector<SurfaceRecord>& surfaces, int resolution = 64);

}  // namespace nonplanar
