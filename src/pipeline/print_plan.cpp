// The print plan as JSON (print_plan.hpp, docs/plan-format.md).
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "nonplanar/config.hpp"
#include "nonplanar/print_plan.hpp"

namespace nonplanar {

using nlohmann::json;
using nlohmann::ordered_json;

namespace {

constexpr int kVersion = 1;

std::string polygon_text(const std::vector<Vec2>& poly) {
  std::string s;
  char buf[64];
  for (const Vec2& p : poly) {
    std::snprintf(buf, sizeof buf, "%s%.17g,%.17g", s.empty() ? "" : ";", p.x(), p.y());
    s += buf;
  }
  return s;
}

ordered_json toolhead_json(const Toolhead& t) {
  ordered_json j = {{"nozzle_tip_radius", t.tip_radius},
                    {"nozzle_cone_angle", t.cone_angle_deg},
                    {"heater_block_radius", t.block_radius},
                    {"heater_block_clearance", t.block_clearance}};
  if (!t.shape.empty()) {
    ordered_json slices = ordered_json::array();
    for (const ToolheadSlice& s : t.shape) {
      ordered_json polys = ordered_json::array();
      for (const auto& p : s.polygons) polys.push_back(polygon_text(p));
      slices.push_back({{"height", s.height}, {"polygons", std::move(polys)}});
    }
    j["shape"] = {{"name", t.shape_name}, {"slices", std::move(slices)}};
  }
  return j;
}

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(what);
}

double number(const json& j, const char* key, double lo, double hi) {
  const json& v = j.at(key);
  if (!v.is_number() || !(v.get<double>() >= lo && v.get<double>() <= hi)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s must be a number from %g to %g", key, lo, hi);
    fail(buf);
  }
  return v.get<double>();
}

std::string text(const json& j, const char* key) {
  const json& v = j.at(key);
  if (!v.is_string() || v.get<std::string>().size() > 4096)
    fail(std::string(key) + " must be a short text");
  return v.get<std::string>();
}

Toolhead read_toolhead(const json& j) {
  Toolhead t;
  t.tip_radius = number(j, "nozzle_tip_radius", 0, 10);
  t.cone_angle_deg = number(j, "nozzle_cone_angle", 1, 90);
  t.block_radius = number(j, "heater_block_radius", 0, 1000);
  t.block_clearance = number(j, "heater_block_clearance", 0, 1000);
  if (j.contains("shape")) {
    const json& s = j.at("shape");
    t.shape_name = text(s, "name");
    auto shape = parse_toolhead_shape(json{{"slices", s.at("slices")}}.dump());
    if (!shape) fail("toolhead shape: " + shape.error().message);
    t.shape = std::move(*shape);
  }
  return t;
}

Vec3 vec3(const json& v) {
  if (!v.is_array() || v.size() != 3) fail("a point must be [x, y, z]");
  Vec3 p;
  for (int k = 0; k < 3; ++k) {
    if (!v[k].is_number() || !std::isfinite(v[k].get<double>()) ||
        std::abs(v[k].get<double>()) > 1e5)
      fail("a point's coordinates must be numbers within 100 m");
    p[k] = v[k].get<double>();
  }
  return p;
}

}  // namespace

std::string plan_json(const PrintPlan& p) {
  ordered_json j = {{"format", "nonplanar-plan"},
                    {"version", kVersion},
                    {"units", "mm"},
                    {"object", p.object},
                    {"model", p.model},
                    {"box",
                     {{"min", {p.box.min.x(), p.box.min.y(), p.box.min.z()}},
                      {"max", {p.box.max.x(), p.box.max.y(), p.box.max.z()}}}},
                    {"layer_height", p.layer_height},
                    {"first_layer_height", p.first_layer_height},
                    {"min_layer_height", p.min_layer_height},
                    {"max_layer_height", p.max_layer_height},
                    {"max_angle", p.max_angle_deg},
                    {"toolhead", toolhead_json(p.toolhead)},
                    {"header", p.header},
                    {"field", ordered_json::parse(p.field)}};
  if (!p.shell.empty()) j["shell"] = ordered_json::parse(p.shell);
  if (!p.anchor.empty()) {
    ordered_json contour = ordered_json::array();
    for (const Vec2& q : p.anchor) contour.push_back({q.x(), q.y()});
    j["anchor"] = {{"z", p.anchor_z}, {"contour", std::move(contour)}};
  }
  return j.dump(1) + "\n";
}

Expected<PrintPlan> parse_plan_json(std::string_view in) {
  const json j = json::parse(in.begin(), in.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("format") ||
      j["format"] != "nonplanar-plan")
    return Error{Status::parse_error, "not a nonplanar-plan document"};
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"] != kVersion)
    return Error{Status::unsupported,
                 "a plan of another version (this nonplanar reads version 1): prepare it again"};
  PrintPlan p;
  try {
    p.object = text(j, "object");
    p.model = text(j, "model");
    p.box.min = vec3(j.at("box").at("min"));
    p.box.max = vec3(j.at("box").at("max"));
    if (p.box.empty()) fail("box: min lies beyond max");
    p.layer_height = number(j, "layer_height", 0.01, 10);
    p.first_layer_height = number(j, "first_layer_height", 0.01, 10);
    p.min_layer_height = number(j, "min_layer_height", 0.01, 10);
    p.max_layer_height = number(j, "max_layer_height", p.min_layer_height, 10);
    p.max_angle_deg = number(j, "max_angle", 0.1, 89.5);
    p.toolhead = read_toolhead(j.at("toolhead"));
    const json& h = j.at("header");
    if (!h.is_array() || h.size() > 1000) fail("header must be a list of lines");
    for (const json& line : h) {
      if (!line.is_string() || line.get<std::string>().size() > 400 ||
          line.get<std::string>().find_first_of("\r\n") != std::string::npos)
        fail("header lines must be short single lines");
      p.header.push_back(line.get<std::string>());
    }
    if (!j.at("field").is_object()) fail("field must be an object");
    p.field = j.at("field").dump();
    if (j.contains("anchor")) {
      const json& a = j.at("anchor");
      p.anchor_z = number(a, "z", 0, 1e5);
      const json& c = a.at("contour");
      if (!c.is_array() || c.size() < 3 || c.size() > 1000000)
        fail("anchor contour must be a list of 3 points or more");
      for (const json& q : c) {
        if (!q.is_array() || q.size() != 2) fail("anchor points must be [x, y]");
        const Vec3 v = vec3(json::array({q[0], q[1], 0}));
        p.anchor.emplace_back(v.x(), v.y());
      }
    }
    if (j.contains("shell")) {
      if (!j.at("shell").is_object()) fail("shell must be an object");
      p.shell = j.at("shell").dump();
    }
  } catch (const std::exception& e) {
    return Error{Status::parse_error, e.what()};
  }
  return p;
}

}  // namespace nonplanar
