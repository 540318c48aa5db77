#include "nonplanar/surface_io.hpp"

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>

#include "core/atomic_file.hpp"
#include "core/file_bytes.hpp"

namespace nonplanar {

using nlohmann::ordered_json;

namespace {

ordered_json to_json(const SurfaceRecord& r) {
  const NurbsSurface& s = r.surface.surface;
  ordered_json pts = ordered_json::array();
  for (const Vec3& p : s.points) pts.push_back({p.x(), p.y(), p.z()});
  ordered_json j = {{"patch", r.patch},
                    {"degree_u", s.p},
                    {"degree_v", s.q},
                    {"count_u", s.n_u},
                    {"count_v", s.n_v},
                    {"knots_u", s.U},
                    {"knots_v", s.V},
                    {"control_points", std::move(pts)},
                    {"weights", s.weights},
                    {"uv_map",
                     {{"origin", {r.surface.origin.x(), r.surface.origin.y()}},
                      {"extent", {r.surface.extent.x(), r.surface.extent.y()}}}},
                    {"rms_error", r.rms_error},
                    {"max_error", r.max_error}};
  if (r.layer >= 0) j["layer"] = r.layer;
  if (r.has_footprint)
    j["footprint"] = {{"xy_min", {r.footprint_min.x(), r.footprint_min.y()}},
                      {"xy_max", {r.footprint_max.x(), r.footprint_max.y()}}};
  return j;
}

// An integer field. nlohmann's get<int>() casts a float such as 2e101 to int, which is undefined
// behaviour (found by fuzz_surfaces under UBSan): only JSON integers that fit are accepted.
int int_at(const nlohmann::json& j, const char* key) {
  const auto& v = j.at(key);
  if (!v.is_number_integer()) throw std::runtime_error(std::string(key) + " must be an integer");
  constexpr auto lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
  const bool fits = v.is_number_unsigned()
                        ? v.get<std::uint64_t>() <= std::uint64_t(hi)
                        : v.get<std::int64_t>() >= lo && v.get<std::int64_t>() <= hi;
  if (!fits) throw std::runtime_error(std::string(key) + " is out of range");
  return int(v.get<std::int64_t>());
}

SurfaceRecord from_json(const nlohmann::json& j) {
  SurfaceRecord r;
  NurbsSurface& s = r.surface.surface;
  r.patch = int_at(j, "patch");
  s.p = int_at(j, "degree_u");
  s.q = int_at(j, "degree_v");
  s.n_u = int_at(j, "count_u");
  s.n_v = int_at(j, "count_v");
  s.U = j.at("knots_u").get<std::vector<double>>();
  s.V = j.at("knots_v").get<std::vector<double>>();
  for (const auto& p : j.at("control_points")) {
    if (!p.is_array() || p.size() != 3) throw std::runtime_error("control point needs 3 numbers");
    s.points.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  }
  s.weights = j.at("weights").get<std::vector<double>>();
  const auto& m = j.at("uv_map");
  r.surface.origin = {m.at("origin").at(0).get<double>(), m.at("origin").at(1).get<double>()};
  r.surface.extent = {m.at("extent").at(0).get<double>(), m.at("extent").at(1).get<double>()};
  r.rms_error = j.value("rms_error", 0.0);
  r.max_error = j.value("max_error", 0.0);
  r.layer = j.contains("layer") ? int_at(j, "layer") : -1;
  if (j.contains("footprint")) {
    const auto& f = j.at("footprint");
    r.has_footprint = true;
    r.footprint_min = {f.at("xy_min").at(0).get<double>(), f.at("xy_min").at(1).get<double>()};
    r.footprint_max = {f.at("xy_max").at(0).get<double>(), f.at("xy_max").at(1).get<double>()};
  }
  return r;
}

}  // namespace

std::string surfaces_json(const std::vector<SurfaceRecord>& surfaces, int indent) {
  ordered_json doc = {{"format", "nonplanar-surfaces"}, {"version", 1}, {"units", "mm"}};
  ordered_json arr = ordered_json::array();
  for (const auto& r : surfaces) arr.push_back(to_json(r));
  doc["surfaces"] = std::move(arr);
  return doc.dump(indent) + "\n";
}

Expected<void> write_surfaces_json(const std::filesystem::path& file,
                                   const std::vector<SurfaceRecord>& surfaces) {
  const std::string text = surfaces_json(surfaces, 1);
  return write_file_atomically(file, [&](std::ostream& out) {
    out << text;
    return bool(out);
  });
}

Expected<std::vector<SurfaceRecord>> parse_surfaces_json(std::string_view text) {
  const auto j = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded()) return Error{Status::parse_error, "not valid JSON"};
  // (json::value() throws when the key holds another type: test the types first. Found by
  // fuzz_surfaces with {"format": 1111}.)
  const auto format = j.is_object() ? j.find("format") : j.end();
  if (format == j.end() || !format->is_string() || *format != "nonplanar-surfaces")
    return Error{Status::parse_error, "not a nonplanar-surfaces document"};
  const auto version = j.find("version");
  if (version == j.end() || !version->is_number_integer() || *version != 1)
    return Error{Status::unsupported, "unknown version"};
  std::vector<SurfaceRecord> out;
  try {
    for (const auto& s : j.at("surfaces")) {
      out.push_back(from_json(s));
      const auto& r = out.back();
      if (!r.surface.surface.valid() || !(r.surface.extent.x() > 0) ||
          !(r.surface.extent.y() > 0) || !r.surface.origin.allFinite() ||
          !r.surface.extent.allFinite())
        return Error{Status::parse_error,
                     "surface " + std::to_string(out.size() - 1) +
                         ": inconsistent degrees, knots, control points or weights"};
    }
  } catch (const std::exception& e) {
    return Error{Status::parse_error, "surface " + std::to_string(out.size()) + ": " + e.what()};
  }
  return out;
}

Expected<std::vector<SurfaceRecord>> read_surfaces_json(const std::filesystem::path& file) {
  auto bytes = core::read_file_bytes(file, 1u << 30);
  if (!bytes) return Error{bytes.error().status, file.string() + ": " + bytes.error().message};
  auto r = parse_surfaces_json(bytes->view());
  if (!r) return Error{r.error().status, file.string() + ": " + r.error().message};
  return r;
}

Expected<void> write_surfaces_obj(const std::filesystem::path& file,
                                  const std::vector<SurfaceRecord>& surfaces, int resolution) {
  resolution = std::max(resolution, 1);
  return write_file_atomically(file, [&](std::ostream& out) {
    out << "# nonplanar fitted surfaces: one group per patch, z = S(u(x), v(y))\n";
    out.precision(9);
    long base = 1;
    for (const auto& r : surfaces) {
      out << "g patch_" << r.patch << "\n";
      const HeightField& h = r.surface;
      for (int i = 0; i <= resolution; ++i)
        for (int j = 0; j <= resolution; ++j) {
          const double x = h.origin.x() + h.extent.x() * i / resolution;
          const double y = h.origin.y() + h.extent.y() * j / resolution;
          out << "v " << x << ' ' << y << ' ' << h.height(x, y) << '\n';
        }
      const int n = resolution + 1;
      for (int i = 0; i < resolution; ++i)
        for (int j = 0; j < resolution; ++j) {
          const long a = base + i * n + j, b = a + n;
          out << "f " << a << ' ' << b << ' ' << b + 1 << "\nf " << a << ' ' << b + 1 << ' '
              << a + 1 << '\n';
        }
      base += static_cast<long>(n) * n;
    }
    return bool(out);
  });
}

}  // namespace nonplanar
