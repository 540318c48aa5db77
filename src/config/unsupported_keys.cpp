// The settings the built-in engine does not do, and the values at which they are inert
// (PrusaSlicer 2.5's defaults): a stock profile that leaves them off is printed silently,
// one that asks for them is told.

#include "nonplanar/unsupported_keys.hpp"

#include <cstdlib>

namespace nonplanar {
namespace {

enum class Inert { zero, text };  // a number that is off at 0, or a text that is off as given

struct Unsupported {
  const char* key;
  Inert inert;
  const char* off;  ///< Inert::text: the inert values, '|'-separated
};

// clang-format off
constexpr Unsupported kUnsupported[] = {
    {"support_material", Inert::zero, ""},
    {"support_material_auto", Inert::zero, ""},  // only with support_material (see below)
    {"raft_layers", Inert::zero, ""},
    {"brim_width", Inert::zero, ""},
    {"ironing", Inert::zero, ""},
    {"spiral_vase", Inert::zero, ""},
    {"complete_objects", Inert::zero, ""},
    {"draft_shield", Inert::text, "disabled|0"},
    {"fuzzy_skin", Inert::text, "none"},
    {"seam_position", Inert::text, "aligned|nearest"},
    {"infill_every_layers", Inert::text, "1|0"},
    {"extra_perimeters", Inert::zero, ""},
    {"ooze_prevention", Inert::zero, ""},
    {"interface_shells", Inert::zero, ""},
};
// clang-format on

const Unsupported* find(const std::string& key) {
  for (const Unsupported& u : kUnsupported)
    if (key == u.key) return &u;
  return nullptr;
}

// The first item of a per-extruder list ("0,0" or "\"none\""), unquoted.
std::string first_item_unquoted(const std::string& v) {
  std::string s = v.substr(0, v.find_first_of(",;"));
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

bool asks_for_something(const Unsupported& u, const std::string& value) {
  const std::string v = first_item_unquoted(value);
  if (u.inert == Inert::zero) return !v.empty() && std::strtod(v.c_str(), nullptr) != 0;
  const std::string off = std::string("|") + u.off + "|";
  return off.find("|" + v + "|") == std::string::npos;
}

}  // namespace

bool is_unsupported_key(const std::string& key) {
  return find(key) != nullptr;
}

std::vector<std::string> unsupported_settings(const PrintConfig& c) {
  std::vector<std::string> out;
  const auto on = [&](const char* key) {
    const auto it = c.profile.find(key);
    return it != c.profile.end() && asks_for_something(*find(key), it->second);
  };
  for (const auto& [key, value] : c.profile) {  // std::map: sorted by key
    const Unsupported* u = find(key);
    if (!u || !asks_for_something(*u, value)) continue;
    // support_material_auto is PrusaSlicer's default 1; it means nothing without supports.
    if (key == "support_material_auto" && !on("support_material")) continue;
    out.push_back(key + " = " + value);
  }
  return out;
}

}  // namespace nonplanar
