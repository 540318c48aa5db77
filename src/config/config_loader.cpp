// Profile files: JSON or PrusaSlicer .ini, chosen by extension.
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/file_bytes.hpp"
#include "nonplanar/config.hpp"

namespace nonplanar {

Expected<PrintConfig> parse_json_config(std::string_view text, PrintConfig c) {
  const auto j = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded()) return Error{Status::parse_error, "not valid JSON"};
  if (!j.is_object()) return Error{Status::parse_error, "a profile must be a JSON object"};
  for (const auto& [key, v] : j.items()) {
    std::string value;
    if (v.is_string())
      value = v.get<std::string>();
    else if (v.is_boolean())
      value = v.get<bool>() ? "1" : "0";
    else if (v.is_number()) {
      const double d = v.get<double>();
      if (!std::isfinite(d)) return Error{Status::invalid_argument, key + ": not a finite number"};
      value = v.dump();
    } else
      return Error{Status::parse_error, key + ": expected a number, string or boolean"};
    auto r = set_config_value(c, prusaslicer_key(key), value);
    if (!r) return r.error();
  }
  if (auto v = validate_config(c); !v) return v.error();
  return c;
}

Expected<PrintConfig> load_config(const std::filesystem::path& file, PrintConfig base) {
  auto bytes = core::read_file_bytes(file, 64u << 20);
  if (!bytes) return Error{bytes.error().status, file.string() + ": " + bytes.error().message};
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return std::tolower(ch); });
  if (ext == ".json" && is_orca_profile(bytes->view())) {
    auto keys = orca_profile_keys(file);
    if (!keys) return keys.error();
    for (const auto& [key, value] : *keys)
      if (auto r = set_config_value(base, key, value); !r)
        return Error{r.error().status, file.string() + ": " + r.error().message};
    if (auto v = validate_config(base); !v)
      return Error{v.error().status, file.string() + ": " + v.error().message};
    return base;
  }
  Expected<PrintConfig> r =
      ext == ".json" ? parse_json_config(bytes->view(), std::move(base))
      : ext == ".ini"
          ? parse_ini_config(bytes->view(), std::move(base))
          : Expected<PrintConfig>(Error{Status::unsupported, "use a .json or .ini profile"});
  if (!r) return Error{r.error().status, file.string() + ": " + r.error().message};
  return r;
}

}  // namespace nonplanar
