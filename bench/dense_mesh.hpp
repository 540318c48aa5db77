// The 1M-triangle benchmark input: a shared model (np_prusa_sphere.stl) subdivided 5 times
// (1280 · 4^5 = 1,310,720 triangles), written as binary STL.
#pragma once

#include <filesystem>
#include <string>

namespace nonplanar::bench {

/// Writes the dense mesh to `out` (binary STL). Returns an empty string or an error line.
std::string write_dense_mesh(const std::filesystem::path& out, int levels = 5);

}  // namespace nonplanar::bench
