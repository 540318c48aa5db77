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
  l.objects = c.gcode.objects;
  if (l.objects.size() < 2)
    l.objects = {{c.gcode.object_name.empty() ? "part" : c.gcode.object_name, 0, 0}};
  return l;
}

namespace {

PlateObject object_of(const ObjectLabels& l, int object) {
  const auto k = static_cast<std::size_t>(object);
  return k < l.objects.size() ? l.objects[k]
                              : PlateObject{"object " + std::to_string(object + 1), object, 0};
}

// "NAME id:ID copy COPY", as PrusaSlicer's comments carry it.
std::string label(const PlateObject& o) {
  return o.name + " id:" + std::to_string(o.id) + " copy " + std::to_string(o.copy);
}

// Klipper's object name: one word of letters, digits and _.- (PrusaSlicer's NAME_id_0_copy_0).
std::string klipper_id(const PlateObject& o) {
  std::string id;
  for (char ch : o.name) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                    (ch >= '0' && ch <= '9') || ch == '_' || ch == '.' || ch == '-';
    id += ok ? ch : '_';
  }
  return id + "_id_" + std::to_string(o.id) + "_copy_" + std::to_string(o.copy);
}

}  // namespace

std::string ObjectLabels::define(const std::vector<LayerToolpaths>& layers) const {
  if (!firmware) return "";
  const std::size_t n = std::max<std::size_t>(objects.size(), 1);
  std::vector<Vec2> min(n, Vec2(1e300, 1e300)), max(n, Vec2(-1e300, -1e300));
  for (const LayerToolpaths& L : layers)
    for (const ExtrusionPath& p : L.paths)
      if (p.role != ExtrusionRole::skirt && static_cast<std::size_t>(p.object) < n)
        for (const Vec3& q : p.points) {
          const auto k = static_cast<std::size_t>(p.object);
          min[k] = min[k].cwiseMin(q.head<2>()), max[k] = max[k].cwiseMax(q.head<2>());
        }
  auto printed = [&](std::size_t k) { return min[k].x() <= max[k].x(); };
  char buf[600];
  if (!klipper) {  // M486 counts the objects; it names none
    bool any = false;
    for (std::size_t k = 0; k < n; ++k) any |= printed(k);
    if (!any) return "";
    std::snprintf(buf, sizeof buf, "M486 T%zu\n", n);
    return buf;
  }
  std::string s;
  for (std::size_t k = 0; k < n; ++k) {
    if (!printed(k)) continue;
    std::snprintf(buf, sizeof buf,
                  "EXCLUDE_OBJECT_DEFINE NAME=%s CENTER=%.3f,%.3f POLYGON=[[%.3f,%.3f],[%.3f,%.3f],"
                  "[%.3f,%.3f],[%.3f,%.3f]]\n",
                  klipper_id(object_of(*this, static_cast<int>(k))).c_str(),
                  0.5 * (min[k].x() + max[k].x()), 0.5 * (min[k].y() + max[k].y()), min[k].x(),
                  min[k].y(), max[k].x(), min[k].y(), max[k].x(), max[k].y(), min[k].x(),
                  max[k].y());
    s += buf;
  }
  return s;
}

std::string ObjectLabels::start(int object) const {
  std::string s;
  const PlateObject o = object_of(*this, object);
  if (comments) s += "; printing object " + label(o) + "\n";
  if (firmware)
    s += klipper ? "EXCLUDE_OBJECT_START NAME=" + klipper_id(o) + "\n"
                 : "M486 S" + std::to_string(object) + "\n";
  return s;
}

std::string ObjectLabels::stop(int object) const {
  std::string s;
  const PlateObject o = object_of(*this, object);
  if (firmware) s += klipper ? "EXCLUDE_OBJECT_END NAME=" + klipper_id(o) + "\n" : "M486 S-1\n";
  if (comments) s += "; stop printing object " + label(o) + "\n";
  return s;
}

}  // namespace nonplanar::gcode
