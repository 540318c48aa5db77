// Head shapes as JSON (docs/toolhead.md): slices of convex polygons by height above the nozzle
// tip, written as PrusaSlicer's printer geometry writes them ("x,y;x,y;…") or as [[x, y], …].
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/file_bytes.hpp"
#include "core/text_tokens.hpp"
#include "nonplanar/config.hpp"

#ifndef NONPLANAR_TOOLHEADS_DIR
#define NONPLANAR_TOOLHEADS_DIR "toolheads"
#endif

namespace nonplanar {
namespace {

constexpr std::size_t kMaxSlices = 64, kMaxPolygons = 64, kMaxVertices = 256;
constexpr double kMaxSize = 1000;  // mm: no head is a metre wide

Error bad(const std::string& why) {
  return Error{Status::parse_error, why};
}

Expected<std::vector<Vec2>> parse_polygon(const nlohmann::json& j, const std::string& where) {
  std::vector<double> xy;
  if (j.is_string()) {
    std::string s = j.get<std::string>();
    for (char& ch : s)
      if (ch == ';' || ch == ',') ch = ' ';
    std::istringstream in(s);
    std::string word;
    while (in >> word) {
      const auto v = core::parse_double(word);
      if (!v) return bad(where + ": '" + word.substr(0, 20) + "' is not a number");
      xy.push_back(*v);
    }
  } else if (j.is_array()) {
    for (const auto& p : j) {
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
        return bad(where + ": a vertex must be [x, y]");
      xy.push_back(p[0].get<double>()), xy.push_back(p[1].get<double>());
    }
  } else {
    return bad(where + ": a polygon is \"x,y;x,y;…\" or [[x, y], …]");
  }
  if (xy.size() % 2 != 0) return bad(where + ": odd number of coordinates");
  std::vector<Vec2> poly;
  for (std::size_t i = 0; i + 1 < xy.size(); i += 2) {
    if (!std::isfinite(xy[i]) || !std::isfinite(xy[i + 1]) || std::abs(xy[i]) > kMaxSize ||
        std::abs(xy[i + 1]) > kMaxSize)
      return bad(where + ": coordinates must be finite and within 1000 mm");
    poly.emplace_back(xy[i], xy[i + 1]);
  }
  if (poly.size() < 3 || poly.size() > kMaxVertices)
    return bad(where + ": a polygon needs 3 to 256 vertices");
  // Convex: every turn the same way (collinear turns allowed), with some area.
  int sign = 0;
  double area = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2 &a = poly[i], &b = poly[(i + 1) % poly.size()], &c = poly[(i + 2) % poly.size()];
    area += a.x() * b.y() - b.x() * a.y();
    const double t = (b - a).x() * (c - b).y() - (b - a).y() * (c - b).x();
    if (t == 0) continue;
    if (sign != 0 && (t > 0) != (sign > 0)) return bad(where + ": the polygon is not convex");
    sign = t > 0 ? 1 : -1;
  }
  if (std::abs(area) < 1e-9) return bad(where + ": the polygon has no area");
  return poly;
}

}  // namespace

Expected<std::vector<ToolheadSlice>> parse_toolhead_shape(std::string_view text) {
  const auto j = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded()) return bad("not valid JSON");
  if (!j.is_object() || !j.contains("slices") || !j["slices"].is_array())
    return bad("a head shape is a JSON object with a \"slices\" array");
  const auto& slices = j["slices"];
  if (slices.empty() || slices.size() > kMaxSlices) return bad("\"slices\": 1 to 64 slices");
  std::vector<ToolheadSlice> out;
  for (std::size_t i = 0; i < slices.size(); ++i) {
    const auto& s = slices[i];
    const std::string where = "slice " + std::to_string(i + 1);
    if (!s.is_object()) return bad(where + ": expected an object");
    ToolheadSlice slice;
    const auto h = s.value("height", nlohmann::json());
    // PrusaSlicer writes heights as strings ("11").
    std::optional<double> height;
    if (h.is_number()) height = h.get<double>();
    if (h.is_string()) height = core::parse_double(h.get<std::string>());
    if (!height || !std::isfinite(*height) || *height < 0 || *height > kMaxSize)
      return bad(where + ": \"height\" must be a number of mm from 0 to 1000");
    slice.height = *height;
    if (s.contains("type") && s["type"] != "convex" && s["type"] != "box")
      return bad(where + ": \"type\" is convex or box");
    if (!s.contains("polygons") || !s["polygons"].is_array() || s["polygons"].empty() ||
        s["polygons"].size() > kMaxPolygons)
      return bad(where + ": \"polygons\" must hold 1 to 64 polygons");
    for (std::size_t k = 0; k < s["polygons"].size(); ++k) {
      auto poly = parse_polygon(s["polygons"][k], where + ", polygon " + std::to_string(k + 1));
      if (!poly) return poly.error();
      slice.polygons.push_back(std::move(*poly));
    }
    out.push_back(std::move(slice));
  }
  return out;
}

Expected<std::vector<ToolheadSlice>> load_toolhead_shape(const std::string& file_or_name) {
  std::filesystem::path file = file_or_name;
  std::error_code ec;
  const bool bare = file_or_name.find('/') == std::string::npos && !file.has_extension();
  if (bare && !std::filesystem::exists(file, ec))
    file = std::filesystem::path(NONPLANAR_TOOLHEADS_DIR) / (file_or_name + ".json");
  auto bytes = core::read_file_bytes(file, 4u << 20);
  if (!bytes) {
    std::string why = bytes.error().message;
    if (bare) why += " (not a file, nor a head in " NONPLANAR_TOOLHEADS_DIR ")";
    return Error{bytes.error().status, file_or_name + ": " + why};
  }
  auto shape = parse_toolhead_shape(bytes->view());
  if (!shape) return Error{shape.error().status, file.string() + ": " + shape.error().message};
  return shape;
}

}  // namespace nonplanar
