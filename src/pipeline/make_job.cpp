// make_job (pipeline.hpp): every stage's parameters built once from the print configuration.
#include <algorithm>
#include <cstdio>

#include "nonplanar/pipeline.hpp"

namespace nonplanar {

SliceJob make_job(const PrintConfig& print, double max_angle_deg) {
  SliceJob j;
  j.print = print;
  j.analysis.max_angle_deg = max_angle_deg;
  j.layers.layer_height = print.slice.layer_height;
  j.layers.first_layer_height = print.slice.first_layer_height;
  j.layers.max_angle_deg = max_angle_deg;
  // A profile's limits are its variable-layer-height limits; a preset whose own layer height
  // lies outside them (MK3S's 0.30mm DRAFT under max 0.25) prints that height, so the curved
  // layers may reach it too.
  const double h = print.slice.layer_height;
  j.layers.min_layer_height = print.min_layer_height > 0 ? std::min(print.min_layer_height, h)
                                                         : std::min(j.analysis.min_layer_height, h);
  j.layers.max_layer_height =
      print.max_layer_height > 0
          ? std::max(print.max_layer_height, h)
          : std::min(print.paths.nozzle_diameter,
                     std::max(1.5 * print.slice.layer_height,
                              std::min(0.75 * print.paths.nozzle_diameter, 0.3)));
  j.analysis.min_layer_height = j.layers.min_layer_height;
  // A layer steeper than the nozzle's outer wall drags the wall through the layer under it
  // (DESIGN.md §3): the cone bounds the slope, for the facets painted and the layers alike.
  const double cone = print.toolhead.cone_angle_deg;
  if (cone < max_angle_deg) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "max_angle lowered from %.1f to %.1f deg: the nozzle's cone "
                  "(nozzle_cone_angle) is no steeper",
                  max_angle_deg, cone);
    j.notices.push_back({Notice::Kind::setting, -1, buf});
    j.analysis.max_angle_deg = j.layers.max_angle_deg = cone;
  }
  j.layers.toolhead = print.toolhead;
  j.layers.shell_layers = print.shell_layers;
  j.layers.shell_max_banded = print.shell_max_banded;
  j.map_back.tip_radius = print.toolhead.tip_radius;
  j.map_back.passes.head = print.toolhead;
  j.map_back.min_layer_height = j.layers.min_layer_height;
  j.map_back.travel_lift = travel_lift(print.gcode.retract_lift);
  j.check = check_params(print, j.layers.max_angle_deg);
  return j;
}

}  // namespace nonplanar
