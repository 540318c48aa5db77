// Object labels (PrusaSlicer's gcode_label_objects): the lines that let a printer or its host
// cancel one object mid-print: the part, or each object of a plate (ExtrusionPath::object).
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
  /// Object k's name, id and copy, as the comments carry them ("NAME id:ID copy COPY"; Klipper's
  /// NAME is a one-word form of the three, the firmware's M486 number is k).
  std::vector<PlateObject> objects;

  /// Before the print: for each object, Klipper's EXCLUDE_OBJECT_DEFINE with the footprint of
  /// its paths (their XY box, mm; the skirt is no object's); or M486 T<objects>.
  std::string define(const std::vector<LayerToolpaths>& layers) const;
  std::string start(int object) const;  ///< before the object's paths in a layer
  std::string stop(int object) const;   ///< after them
};

/// From gcode_label_objects as each PrusaSlicer writes it: firmware (2.6: both kinds), 1
/// (2.5) or octoprint (comments only), 0 or disabled or absent (none); the objects of
/// GcodeParams::objects, or the one object GcodeParams::object_name.
ObjectLabels object_labels(const PrintConfig& c);

}  // namespace nonplanar::gcode
