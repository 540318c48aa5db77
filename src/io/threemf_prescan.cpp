// prescan_3mf (threemf_prescan.hpp): tags counted in the model XML, components expanded with
// memoised counts. Only the 3MF core's unprefixed names are looked for; a package using
// others (or the production extension's p:path) is left to lib3mf.
#include "io/threemf_prescan.hpp"

#include <cstdlib>
#include <string>
#include <unordered_map>
#include <vector>

#include "io/zip_package.hpp"

namespace nonplanar::io {
namespace {

constexpr std::size_t kMaxModelPart = std::size_t(1) << 30;  // lib3mf holds more than this

struct Object {
  double triangles = 0;
  std::vector<long> children;
  int state = 0;  // 0 unseen, 1 on the walk, 2 counted
  BuildCount count;
};

// The value of attribute `name` (with its leading space) in the tag text, or -1.
long id_attribute(std::string_view tag, std::string_view name) {
  const std::size_t at = tag.find(name);
  if (at == std::string_view::npos) return -1;
  const char* p = tag.data() + at + name.size();
  char* end = nullptr;
  const long v = std::strtol(p, &end, 10);
  return end == p || v < 0 ? -1 : v;
}

// The counts of object `id` with its components expanded; false (and *error) when it cannot
// be. (References into the map stay valid: nothing is inserted while expanding.)
bool expand(std::unordered_map<long, Object>& objects, long id, int depth, BuildCount* out,
            std::string* error) {
  auto it = objects.find(id);
  if (it == objects.end())
    return *error = "an item or component names object " + std::to_string(id) +
                    ", which is not in the model",
           false;
  Object& o = it->second;
  if (o.state == 2) return *out = o.count, true;
  if (o.state == 1 || depth > 32)
    return *error = "components nested more than 32 deep, or in a cycle", false;
  o.state = 1;
  BuildCount c{o.triangles, 1, {}};
  for (long child : o.children) {
    BuildCount sub;
    if (!expand(objects, child, depth + 1, &sub, error)) return false;
    c.triangles += sub.triangles, c.instances += sub.instances;
  }
  o.state = 2, o.count = c;
  *out = c;
  return true;
}

// The model part the package's root relationship names (3D/3dmodel.model by convention).
std::string root_part(std::string_view zip) {
  const auto rels = zip_entry(zip, "_rels/.rels", 1 << 20);
  const std::string kType = "3dmanufacturing/2013/01/3dmodel\"";
  std::size_t at = rels ? rels->find(kType) : std::string::npos;
  if (at == std::string::npos) return "3D/3dmodel.model";
  const std::size_t open = rels->rfind("<Relationship", at);
  const std::size_t close = rels->find('>', at);
  const std::size_t target = rels->find("Target=\"", open);
  if (open == std::string::npos || target == std::string::npos || target > close)
    return "3D/3dmodel.model";
  const std::size_t b = target + 8, e = rels->find('"', b);
  return rels->substr(b, e - b);
}

}  // namespace

std::optional<BuildCount> prescan_3mf(std::string_view zip) {
  auto part = zip_entry(zip, root_part(zip), kMaxModelPart);
  if (!part || part->find("p:path") != std::string::npos) return std::nullopt;
  const std::string_view xml = *part;
  std::unordered_map<long, Object> objects;
  std::vector<long> items;
  long current = -1;
  for (std::size_t at = xml.find('<'); at != std::string_view::npos; at = xml.find('<', at + 1)) {
    const std::size_t end = xml.find('>', at);
    if (end == std::string_view::npos) break;
    const std::string_view tag = xml.substr(at, end - at);
    if (tag.rfind("<triangle ", 0) == 0 && current >= 0) {
      objects[current].triangles += 1;
    } else if (tag.rfind("<object ", 0) == 0) {
      current = id_attribute(tag, " id=\"");
      if (current < 0) return BuildCount{0, 0, "an object without an id"};
      objects[current];
    } else if (tag.rfind("</object", 0) == 0) {
      current = -1;
    } else if (tag.rfind("<component ", 0) == 0 && current >= 0) {
      objects[current].children.push_back(id_attribute(tag, " objectid=\""));
    } else if (tag.rfind("<item ", 0) == 0) {
      items.push_back(id_attribute(tag, " objectid=\""));
    }
  }
  BuildCount total;
  for (long id : items) {
    BuildCount c;
    if (!expand(objects, id, 0, &c, &total.error)) return total;
    total.triangles += c.triangles, total.instances += c.instances;
  }
  return total;
}

}  // namespace nonplanar::io
