// Object labels (PrusaSlicer's gcode_label_objects): the lines that let a printer or its host
// cancel one object mid-print. The built-in engine prints one object, the whole part.
#pragma once

#include <string>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar::gcode {

struct ObjectLabels {
  bool comments = false;  ///< "; printing object NAME id:0 copy 0" (OctoPrint's)
  bool firmware = false;  ///< M486 (Marlin, RepRapFirmware) or EXCLUDE_OBJECT_* (Klipper)
  bool klipper = false;
  std::string name;  ///< as the comments carry it; `id` is the firmware's form of it

  /// Before the print: Klipper's EXCLUDE_OBJECT_DEFINE with the footprint of the layers'
  /// paths but the skirt (their XY box, mm), or M486 T1.
  std::string define(const std::vector<LayerToolpaths>& layers) const;
  std::string start() const;  ///< before the object's paths of a layer
  std::string stop() const;   ///< after them
};

/// From gcode_label_objects as each PrusaSlicer writes it: firmware (2.6: both kinds), 1
/// (2.5) or octoprint (comments only), 0 or disabled or absent (none); the object named
/// GcodeParams::object_name.
ObjectLabels object_labels(const PrintConfig& c);

}  // namespace nonplanar::gcode
