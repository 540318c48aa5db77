#pragma once
// PrusaSlicer settings that change what is printed and that the built-in engine does not do.
// The built-in engine says so instead of printing without them; `--engine prusaslicer`
// prints them (it slices the normalised mesh with the user's own profile).

#include <string>
#include <vector>

#include "nonplanar/config.hpp"

namespace nonplanar {

/// Is `key` a PrusaSlicer setting the built-in engine knows of but does not do (supports,
/// brim, raft, ironing, seam placement, ...)? Such a key is accepted (and named), not
/// "unknown".
bool is_unsupported_key(const std::string& key);

/// The unsupported settings in `c.profile` whose values ask for something (support_material
/// = 1, brim_width > 0, seam_position other than aligned, ...), as "key = value", sorted by
/// key. Output: empty when the built-in engine prints everything the profile asks for.
std::vector<std::string> unsupported_settings(const PrintConfig& c);

}  // namespace nonplanar
