// Presets by name from a vendor bundle, as PrusaSlicer ships them (PrusaResearch.ini,
// Creality.ini, … in /usr/share/PrusaSlicer/profiles): sections [printer:NAME], [print:NAME],
// [filament:NAME], each with `inherits = A; B` applied first (parents in order, later ones
// winning), abstract parents (*common*) included.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

/// Where PrusaSlicer's installed bundles are (Debian's prusa-slicer package).
inline const char* kDefaultProfilesDir = "/usr/share/PrusaSlicer/profiles";

/// The key = value pairs of preset `name` of `type` ("printer", "print" or "filament"),
/// inheritance resolved, plus PrusaSlicer's own record of the choice (printer_settings_id,
/// print_settings_id or filament_settings_id). `where` is a bundle .ini or a folder of them
/// (searched in name order). Errors (not_found, parse_error) name the preset and the file.
Expected<std::vector<std::pair<std::string, std::string>>> find_preset(
    const std::filesystem::path& where, const std::string& type, const std::string& name);

/// find_preset, then each key applied over `base` (set_config_value; keys we do not use are
/// kept in PrintConfig::profile). The result is not validated: later profiles may fix it.
Expected<PrintConfig> apply_preset(const std::filesystem::path& where, const std::string& type,
                                   const std::string& name, PrintConfig base);

}  // namespace nonplanar
