#include "gcode/object_labels.hpp"

#include <cstdio>

namespace nonplanar::gcode {

ObjectLabels object_labels(const PrintConfig& c) {
  ObjectLabels l;
  const auto it = c.profile.find("gcode_label_objects");
  const std::string v = it == c.profile.end() ? "" : it->second;
  l.comments = v == "1" || v == "firmware" || v == "octoprint";
  l.firmware = v == "firmware";  // 2.6's; 2.5's "1" wrote the comments only, as here
  l.klipper = c.gcode.flavor == GcodeFlavor::klipper;
  l.name = c.gcode.object_name.empty() ? "part" : c.gcode.object_name;
  return l;
}

namespace {
// Klipper's object name: one word of letters, digits and _.- (PrusaSlicer's NAME_id_0_copy_0).
std::string klipper_id(const std::string& name) {
  std::string id;
  for (char ch : name) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                    (ch >= '0' && ch <= '9') || ch == '_' || ch == '.' || ch == '-';
    id += ok ? ch : '_';
  }
  return id + "_id_0_copy_0";
}
}  // namespace

std::string ObjectLabels::define(const std::vector<LayerToolpaths>& layers) const {
  if (!firmware) return "";
  Vec2 min(1e300, 1e300), max(-1e300, -1e300);
  for (const LayerToolpaths& L : layers)
    for (const ExtrusionPath& p : L.paths)
      if (p.role != ExtrusionRole::skirt)
        for (const Vec3& q : p.points)
          min = min.cwiseMin(q.head<2>()), max = max.cwiseMax(q.head<2>());
  if (min.x() > max.x()) return "";
  char buf[400];
  if (klipper)
    std::snprintf(buf, sizeof buf,
                  "EXCLUDE_OBJECT_DEFINE NAME=%s CENTER=%.3f,%.3f POLYGON=[[%.3f,%.3f],[%.3f,%.3f],"
                  "[%.3f,%.3f],[%.3f,%.3f]]\n",
                  klipper_id(name).c_str(), 0.5 * (min.x() + max.x()), 0.5 * (min.y() + max.y()),
                  min.x(), min.y(), max.x(), min.y(), max.x(), max.y(), min.x(), max.y());
  else
    std::snprintf(buf, sizeof buf, "M486 T1\n");
  return buf;
}

std::string ObjectLabels::start() const {
  std::string s;
  if (comments) s += "; printing object " + name + " id:0 copy 0\n";
  if (firmware) s += klipper ? "EXCLUDE_OBJECT_START NAME=" + klipper_id(name) + "\n" : "M486 S0\n";
  return s;
}

std::string ObjectLabels::stop() const {
  std::string s;
  if (firmware) s += klipper ? "EXCLUDE_OBJECT_END NAME=" + klipper_id(name) + "\n" : "M486 S-1\n";
  if (comments) s += "; stop printing object " + name + " id:0 copy 0\n";
  return s;
}

}  // namespace nonplanar::gcode
