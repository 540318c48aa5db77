// Vendor bundles: sections of key = value lines, resolved through `inherits`.
#include "nonplanar/presets.hpp"

#include <algorithm>
#include <map>

#include "core/file_bytes.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;
using Keys = std::vector<std::pair<std::string, std::string>>;

struct Bundle {
  std::map<std::string, Keys> sections;  ///< "printer:NAME" → its own keys, in order
};

std::string trim(std::string s) {
  s.erase(0, s.find_first_not_of(" \t"));
  s.erase(s.find_last_not_of(" \t\r") + 1);
  return s;
}

Bundle parse_bundle(std::string_view text) {
  Bundle b;
  Keys* cur = nullptr;
  for (std::size_t p = 0; p < text.size();) {
    const std::size_t e = std::min(text.find('\n', p), text.size());
    const std::string l = trim(std::string(text.substr(p, e - p)));
    p = e + 1;
    if (l.empty() || l[0] == '#' || l[0] == ';') continue;
    if (l.front() == '[' && l.back() == ']') {
      cur = &b.sections[l.substr(1, l.size() - 2)];
      continue;
    }
    const auto eq = l.find('=');
    if (cur && eq != std::string::npos)
      cur->emplace_back(trim(l.substr(0, eq)), trim(l.substr(eq + 1)));
  }
  return b;
}

// Applies section `id` with its parents first into `out` (a key set later wins).
Expected<void> resolve(const Bundle& b, const std::string& type, const std::string& name,
                       std::map<std::string, std::string>& out, int depth) {
  if (depth > 32) return Error{Status::parse_error, name + ": inherits goes round in a circle"};
  const auto it = b.sections.find(type + ":" + name);
  if (it == b.sections.end())
    return Error{Status::invalid_argument, "no " + type + " preset '" + name + "'"};
  for (const auto& [k, v] : it->second) {
    if (k != "inherits") continue;
    std::size_t p = 0;
    while (p <= v.size()) {
      const std::size_t q = std::min(v.find(';', p), v.size());
      std::string parent = trim(v.substr(p, q - p));
      if (parent.size() >= 2 && parent.front() == '"' && parent.back() == '"')
        parent = parent.substr(1, parent.size() - 2);
      if (!parent.empty())
        if (auto r = resolve(b, type, parent, out, depth + 1); !r) return r;
      p = q + 1;
    }
  }
  for (const auto& [k, v] : it->second) out[k] = v;
  return {};
}

}  // namespace

Expected<Keys> find_preset(const fs::path& where, const std::string& type,
                           const std::string& name) {
  if (type != "printer" && type != "print" && type != "filament")
    return Error{Status::invalid_argument, "'" + type + "' is not printer, print or filament"};
  std::vector<fs::path> files;
  std::error_code ec;
  if (fs::is_directory(where, ec)) {
    for (const auto& entry : fs::directory_iterator(where, ec))
      if (entry.path().extension() == ".ini") files.push_back(entry.path());
    std::sort(files.begin(), files.end());
  } else {
    files.push_back(where);
  }
  if (files.empty())
    return Error{Status::invalid_argument, where.string() + ": no vendor bundles (.ini) here"};
  for (const fs::path& f : files) {
    auto bytes = core::read_file_bytes(f, 64u << 20);
    if (!bytes) return Error{bytes.error().status, f.string() + ": " + bytes.error().message};
    const Bundle b = parse_bundle(bytes->view());
    if (!b.sections.count(type + ":" + name)) continue;
    std::map<std::string, std::string> keys;
    if (auto r = resolve(b, type, name, keys, 0); !r)
      return Error{r.error().status, f.string() + ": " + r.error().message};
    Keys out;
    for (auto& [k, v] : keys)
      if (k != "inherits" && k != "renamed_from" && k.rfind("compatible_", 0) != 0 &&
          k.rfind("default_", 0) != 0)
        out.emplace_back(k, v);
    out.emplace_back(type + "_settings_id", type == "filament" ? "\"" + name + "\"" : name);
    return out;
  }
  return Error{Status::invalid_argument,
               "no " + type + " preset '" + name + "' in " + where.string()};
}

Expected<PrintConfig> apply_preset(const fs::path& where, const std::string& type,
                                   const std::string& name, PrintConfig base) {
  auto keys = find_preset(where, type, name);
  if (!keys) return keys.error();
  for (const auto& [k, v] : *keys) {
    auto r = set_config_value(base, k, v);
    if (!r) return Error{r.error().status, type + " preset '" + name + "': " + r.error().message};
  }
  return base;
}

}  // namespace nonplanar
