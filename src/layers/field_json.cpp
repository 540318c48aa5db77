// The layer field as JSON (include/nonplanar/field_io.hpp, docs/plan-format.md). The bands'
// top surfaces are one embedded nonplanar-surfaces document (docs/surface-format.md); scalars
// are written in their shortest round-trip form, arrays as base64 doubles.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/base64.hpp"
#include "layers/banded_field.hpp"
#include "layers/shell_plan.hpp"
#include "nonplanar/field_io.hpp"
#include "nonplanar/surface_io.hpp"

namespace nonplanar {

using layers::Band;
using layers::BandedField;
using nlohmann::json;
using nlohmann::ordered_json;

namespace {

// Rasters and stacks a plan may hold: far beyond any real part (a 300 mm patch at 0.1 mm is
// 9 million nodes, which faceted_top coarsens to about 2 million), small enough that a hostile
// file cannot ask for gigabytes.
constexpr std::int64_t kMaxNodes = 4'000'000;
constexpr int kMaxLayers = 10'000;

// Arrays of doubles as base64 of their IEEE-754 little-endian bytes: exact, and a raster of
// a million nodes is one string to parse, not a million numbers (the bunny's plan: 15 MB of
// text and 520 MB to read it back, before).
std::string doubles_b64(const double* v, std::size_t n) {
  std::string bytes(n * 8, '\0');
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t u;
    std::memcpy(&u, &v[i], 8);
    for (int k = 0; k < 8; ++k) bytes[i * 8 + k] = static_cast<char>((u >> (8 * k)) & 0xff);
  }
  return core::base64_encode(bytes);
}

std::vector<double> b64_doubles(const std::string& s, std::size_t n, const char* what) {
  if (s.size() != (n * 8 + 2) / 3 * 4)
    throw std::runtime_error(std::string(what) + " must hold " + std::to_string(n) + " numbers");
  std::string bytes;
  bytes.reserve(n * 8 + 2);
  for (std::size_t i = 0; i < s.size(); i += 4) {
    std::uint32_t w = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const char c = s[i + k];
      const char* at = c == '=' ? nullptr : std::strchr(core::kBase64Alphabet, c);
      if (c != '=' && (!at || c == '\0'))
        throw std::runtime_error(std::string(what) + " is not base64");
      w = (w << 6) | (at ? static_cast<std::uint32_t>(at - core::kBase64Alphabet) : 0u);
    }
    for (int k = 2; k >= 0; --k) bytes += static_cast<char>((w >> (8 * k)) & 0xff);
  }
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t u = 0;
    for (int k = 0; k < 8; ++k)
      u |= std::uint64_t(static_cast<unsigned char>(bytes[i * 8 + k])) << (8 * k);
    std::memcpy(&out[i], &u, 8);
    if (!std::isfinite(out[i]))
      throw std::runtime_error(std::string(what) + " holds a value that is not a number");
  }
  return out;
}

ordered_json raster(const Vec2& origin, double cell, int nx, int ny,
                    const std::vector<double>& values) {
  return {{"origin", {origin.x(), origin.y()}},
          {"cell", cell},
          {"nx", nx},
          {"ny", ny},
          {"values", doubles_b64(values.data(), values.size())}};
}

ordered_json band_json(const Band& b, int top) {
  ordered_json j = {
      {"top", top},
      {"c", b.c},
      {"T_bottom", b.T_bottom},
      {"N", b.N},
      {"fade", b.fade},
      {"top_lo", b.top_lo},
      {"top_hi", b.top_hi},
      {"control_heights",  // column-major, as Eigen holds it
       {{"rows", b.Z.rows()},
        {"cols", b.Z.cols()},
        {"values", doubles_b64(b.Z.data(), static_cast<std::size_t>(b.Z.size()))}}},
      {"blend", raster(b.blend_origin, b.blend_cell, b.blend_nx, b.blend_ny, b.blend)}};
  if (!b.facets.empty()) {
    ordered_json f = raster(b.facets.origin, b.facets.cell, b.facets.nx, b.facets.ny, b.facets.h);
    f["h_lo"] = b.facets.h_lo, f["h_hi"] = b.facets.h_hi;
    j["facets"] = std::move(f);
  }
  return j;
}

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(what);
}

double number(const json& j, const char* key) {
  const json& v = j.at(key);
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    fail(std::string(key) + " is not a number");
  return v.get<double>();
}

int count(const json& j, const char* key, std::int64_t hi) {
  const json& v = j.at(key);
  if (!v.is_number_integer() || v.get<std::int64_t>() < 0 || v.get<std::int64_t>() > hi)
    fail(std::string(key) + " is not a count up to " + std::to_string(hi));
  return static_cast<int>(v.get<std::int64_t>());
}

std::vector<double> numbers(const json& v, std::size_t n, const char* what) {
  if (v.is_string()) return b64_doubles(v.get<std::string>(), n, what);
  if (!v.is_array() || v.size() != n)
    fail(std::string(what) + " must hold " + std::to_string(n) + " numbers");
  std::vector<double> out;
  out.reserve(n);
  for (const json& x : v) {
    if (!x.is_number() || !std::isfinite(x.get<double>()))
      fail(std::string(what) + " holds a value that is not a number");
    out.push_back(x.get<double>());
  }
  return out;
}

// A raster's grid; its values must number nx · ny (`extra` more nodes per axis for none).
void read_raster(const json& j, const Vec2& shift, Vec2* origin, double* cell, int* nx, int* ny,
                 std::vector<double>* values) {
  const auto o = numbers(j.at("origin"), 2, "origin");
  *origin = Vec2(o[0], o[1]) + shift;
  *cell = number(j, "cell");
  if (!(*cell > 1e-4 && *cell < 1e3)) fail("cell must lie in (0.0001, 1000) mm");
  *nx = count(j, "nx", kMaxNodes), *ny = count(j, "ny", kMaxNodes);
  if (static_cast<std::int64_t>(*nx) * *ny > kMaxNodes) fail("raster has too many nodes");
  *values = numbers(j.at("values"), static_cast<std::size_t>(*nx) * *ny, "values");
}

Band read_band(const json& j, const std::vector<SurfaceRecord>& tops, const Vec2& shift) {
  Band b;
  const int top = count(j, "top", static_cast<std::int64_t>(tops.size()) - 1);
  b.top = tops[top].surface;
  if (b.top.surface.p > 7 || b.top.surface.q > 7) fail("top surface degree above 7");
  b.top.origin += shift;
  for (Vec3& p : b.top.surface.points) p.head<2>() += shift;
  b.c = number(j, "c"), b.T_bottom = number(j, "T_bottom"), b.fade = number(j, "fade");
  b.N = count(j, "N", kMaxLayers);
  if (b.N < 1) fail("N must be at least 1");
  if (!(b.fade > 0)) fail("fade must be positive");
  b.top_lo = number(j, "top_lo"), b.top_hi = number(j, "top_hi");
  const json& z = j.at("control_heights");
  const int rows = count(z, "rows", kMaxLayers + 1), cols = count(z, "cols", kMaxNodes);
  if (rows != b.N + 1 || cols != static_cast<int>(b.top.surface.points.size()))
    fail("control_heights must be (N + 1) x the top's control points");
  const auto zv = numbers(z.at("values"), static_cast<std::size_t>(rows) * cols, "control_heights");
  b.Z = Eigen::Map<const Eigen::MatrixXd>(zv.data(), rows, cols);
  read_raster(j.at("blend"), shift, &b.blend_origin, &b.blend_cell, &b.blend_nx, &b.blend_ny,
              &b.blend);
  for (double v : b.blend)
    if (v < 0 || v > 1) fail("blend values must lie in [0, 1]");
  if (j.contains("facets")) {
    const json& f = j.at("facets");
    layers::FacetedTop& t = b.facets;
    read_raster(f, shift, &t.origin, &t.cell, &t.nx, &t.ny, &t.h);
    if (t.nx < 2 || t.ny < 2) fail("facets raster needs 2 x 2 nodes at least");
    t.h_lo = number(f, "h_lo"), t.h_hi = number(f, "h_hi");
  }
  return b;
}

}  // namespace

Expected<std::string> layer_field_json(const LayerField& field) {
  const auto* banded = dynamic_cast<const BandedField*>(&field);
  if (!banded) return Error{Status::unsupported, "this layer field has no text form"};
  std::vector<SurfaceRecord> tops;
  ordered_json bands = ordered_json::array();
  for (const Band& b : banded->bands()) {
    SurfaceRecord r;
    r.patch = static_cast<int>(tops.size());
    r.surface = b.top;
    tops.push_back(std::move(r));
    bands.push_back(band_json(b, static_cast<int>(tops.size()) - 1));
  }
  ordered_json j = {
      {"planar",
       {{"first_layer_height", banded->planar().h1}, {"layer_height", banded->planar().h}}},
      {"tops", ordered_json::parse(surfaces_json(tops))},
      {"bands", std::move(bands)}};
  return j.dump();
}

Expected<std::shared_ptr<const LayerField>> parse_layer_field_json(std::string_view text,
                                                                   const Vec2& shift) {
  if (!shift.allFinite()) return Error{Status::invalid_argument, "field: shift is not finite"};
  const json j = json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    return Error{Status::parse_error, "field: not a JSON object"};
  try {
    const json& pl = j.at("planar");
    layers::PlanarLayers planar{number(pl, "first_layer_height"), number(pl, "layer_height")};
    if (!(planar.h1 >= 0.01 && planar.h1 <= 10 && planar.h >= 0.01 && planar.h <= 10))
      fail("layer heights must lie in [0.01, 10] mm");
    auto tops = parse_surfaces_json(j.at("tops").dump());
    if (!tops) fail("tops: " + tops.error().message);
    std::vector<Band> bands;
    const json& bj = j.at("bands");
    if (!bj.is_array() || bj.size() > 1000) fail("bands must be a list of at most 1000");
    for (const json& b : bj) {
      try {
        bands.push_back(read_band(b, *tops, shift));
      } catch (const std::exception& e) {
        fail("band " + std::to_string(bands.size()) + ": " + e.what());
      }
    }
    return std::shared_ptr<const LayerField>(
        std::make_shared<BandedField>(planar, std::move(bands)));
  } catch (const std::exception& e) {
    return Error{Status::parse_error, std::string("field: ") + e.what()};
  }
}

namespace layers {

std::string shell_plan_json(const ShellPlan& s) {
  ordered_json top = raster(s.top.origin, s.top.cell, s.top.nx, s.top.ny, s.top.h);
  top["h_lo"] = s.top.h_lo, top["h_hi"] = s.top.h_hi;
  ordered_json j = {
      {"patches", s.patches},
      {"N", s.N},
      {"t", s.t},
      {"reach", s.reach},
      {"core", {{"count", s.core.size()}, {"values", doubles_b64(s.core.data(), s.core.size())}}},
      {"top", std::move(top)}};
  return j.dump();
}

Expected<ShellPlan> parse_shell_plan_json(std::string_view text, const Vec2& shift) {
  if (!shift.allFinite()) return Error{Status::invalid_argument, "shell: shift is not finite"};
  const json j = json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    return Error{Status::parse_error, "shell: not a JSON object"};
  ShellPlan s;
  try {
    const json& patches = j.at("patches");
    if (!patches.is_array() || patches.size() > 10000) fail("patches must be a list");
    for (const json& p : patches) {
      if (!p.is_number_integer() || p.get<std::int64_t>() < 0 || p.get<std::int64_t>() > 1000000)
        fail("patches must be patch numbers");
      s.patches.push_back(p.get<int>());
    }
    s.N = count(j, "N", 1000);
    if (s.N < 1) fail("N must be at least 1");
    s.t = number(j, "t");
    if (!(s.t >= 0.01 && s.t <= 10)) fail("t must lie in [0.01, 10] mm");
    s.reach = number(j, "reach");
    if (!(s.reach >= 0 && s.reach < s.t)) fail("reach must lie in [0, t)");
    const json& core = j.at("core");
    const int n = count(core, "count", kMaxLayers);
    s.core = numbers(core.at("values"), static_cast<std::size_t>(n), "core");
    if (n < 2 || s.core.front() != 0) fail("core must run from 0 over one layer at least");
    for (int k = 1; k < n; ++k)
      if (!(s.core[k] > s.core[k - 1] && s.core[k] < 1e4)) fail("core must rise, below 10 m");
    const json& top = j.at("top");
    read_raster(top, shift, &s.top.origin, &s.top.cell, &s.top.nx, &s.top.ny, &s.top.h);
    if (s.top.nx < 2 || s.top.ny < 2) fail("top raster needs 2 x 2 nodes at least");
    s.top.h_lo = number(top, "h_lo"), s.top.h_hi = number(top, "h_hi");
    for (double h : s.top.h)
      if (std::abs(h) > 1e4) fail("top heights must lie within 10 m");
  } catch (const std::exception& e) {
    return Error{Status::parse_error, std::string("shell: ") + e.what()};
  }
  return s;
}

}  // namespace layers
}  // namespace nonplanar
