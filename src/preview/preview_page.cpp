// The preview page: viewer.html with the buffers, mesh, marks and numbers as one JSON
// document in it (arrays as base64 of their little-endian bytes; preview.hpp).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/base64.hpp"
#include "nonplanar/preview.hpp"
#include "preview/viewer_html.hpp"

namespace nonplanar {
namespace {

template <class T>
std::string b64(const std::vector<T>& v) {
  static_assert(std::is_arithmetic_v<T>);
  std::string bytes(v.size() * sizeof(T), '\0');
  // Little-endian on every machine this builds for (x86-64, arm64); the page reads it so.
  if (!v.empty()) std::memcpy(bytes.data(), v.data(), bytes.size());
  return core::base64_encode(bytes);
}

nlohmann::json box_json(const BoundingBox& b) {
  if (b.empty()) return {0, 0, 0, 1, 1, 1};
  return {b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z()};
}

nlohmann::json mesh_json(const TriangleMesh& mesh) {
  BoundingBox box;
  for (const Vec3& v : mesh.vertices) box.extend(v);
  const Vec3 size = box.size();
  std::vector<std::uint16_t> q;
  q.reserve(mesh.vertices.size() * 3);
  for (const Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) {
      const double t = size[a] > 0 ? (v[a] - box.min[a]) / size[a] : 0.0;
      q.push_back(static_cast<std::uint16_t>(std::lround(std::clamp(t, 0.0, 1.0) * 65535)));
    }
  std::vector<std::uint32_t> f;
  f.reserve(mesh.faces.size() * 3);
  for (const auto& face : mesh.faces)
    for (int i : face) f.push_back(static_cast<std::uint32_t>(i));
  return {{"box", box_json(box)}, {"vertices", b64(q)}, {"faces", b64(f)}};
}

std::string points_b64(const std::vector<Vec3>& points) {
  std::vector<float> v;
  for (const Vec3& p : points)
    for (int a = 0; a < 3; ++a) v.push_back(static_cast<float>(p[a]));
  return b64(v);
}

}  // namespace

std::string preview_html(const PreviewBuffers& b, const TriangleMesh* mesh,
                         const PreviewMarks& marks, const PreviewSummary& summary) {
  nlohmann::ordered_json j = {
      {"title", summary.title},
      {"layers", b.layers},
      {"curved_layers", b.curved_layers},
      {"seconds", b.seconds},
      {"filament_mm", b.filament_mm},
      {"filament_g", summary.filament_g},
      {"p95", summary.p95},
      {"collisions", summary.collisions},
      {"max_angle", summary.max_angle_deg},
      {"box", box_json(b.box)},
      {"bed", summary.bed},
      {"segments", b.segments()},
      {"ends", b64(b.ends)},
      {"layer", b64(b.layer)},
      {"role", b64(b.role)},
      {"flags", b64(b.flags)},
      {"thickness", b64(b.thickness)},
      {"width", b64(b.width)},
      {"slope", b64(b.slope)},
      {"time", b64(b.time)},
      {"role_names", b.role_names},
      {"layer_z", b64(b.layer_z)},
      {"mesh", mesh && !mesh->faces.empty() ? mesh_json(*mesh) : nlohmann::json(nullptr)},
      {"marks",
       {{"collisions", points_b64(marks.collisions)}, {"breaches", points_b64(marks.breaches)}}},
  };
  // Inside <script>, "</" would end the element: JSON may say "<" as \u003c. Invalid UTF-8
  // in a name read from the file is replaced, not thrown on.
  std::string data = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string safe;
  safe.reserve(data.size());
  for (char c : data) {
    if (c == '<')
      safe += "\\u003c";
    else
      safe.push_back(c);
  }
  std::string page = preview::viewer_html();
  const std::string marker = "/*NP_DATA*/";
  page.replace(page.find(marker), marker.size(), safe);
  return page;
}

}  // namespace nonplanar
