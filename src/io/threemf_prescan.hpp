// A first look at a 3MF's model part before lib3mf reads it: lib3mf 1.8 walks nested
// components once per object while reading (exponential in the nesting), and cannot be
// cancelled, so a component bomb of a few KB must be refused before it is handed over.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace nonplanar::io {

/// What the build of the package's root model part (3D/3dmodel.model) expands to, read from
/// its XML alone: triangles, and object instances (every component path, meshes or not).
struct BuildCount {
  double triangles = 0, instances = 0;
  std::string error;  ///< not empty: the build cannot be expanded (a component cycle, nesting
                      ///< deeper than 32, an item or component naming no object)
};

/// The counts. nullopt when the package cannot be looked at this way (not a zip this reader
/// takes, a model part over 1 GB, objects in other parts): lib3mf then reads it as before,
/// and the count after it still applies.
std::optional<BuildCount> prescan_3mf(std::string_view zip);

}  // namespace nonplanar::io
