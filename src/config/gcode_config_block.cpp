// The settings PrusaSlicer appends to its G-code, read back as a profile.
#include "nonplanar/config.hpp"

namespace nonplanar {

std::string gcode_config_block(std::string_view gcode) {
  // PrusaSlicer's block, else OrcaSlicer's (its keys renamed to PrusaSlicer's).
  bool orca = false;
  std::string_view begin = "; prusaslicer_config = begin", end = "; prusaslicer_config = end";
  // It is the file's last part: search from the end, so a long file costs nothing more.
  std::size_t b = gcode.rfind(begin);
  if (b == std::string_view::npos) {
    begin = "; CONFIG_BLOCK_START", end = "; CONFIG_BLOCK_END", orca = true;
    b = gcode.rfind(begin);
  }
  if (b == std::string_view::npos || (b > 0 && gcode[b - 1] != '\n')) return {};
  const std::size_t e = gcode.find(end, b);
  if (e == std::string_view::npos) return {};
  std::string ini;
  for (std::size_t p = gcode.find('\n', b); p != std::string_view::npos && p < e;) {
    const std::size_t q = std::min(gcode.find('\n', p + 1), e);
    std::string_view line = gcode.substr(p + 1, q - p - 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.rfind("; ", 0) == 0) {
      line.remove_prefix(2);
      const std::size_t eq = line.find(" = ");
      if (orca && eq != std::string_view::npos)
        ini += prusaslicer_key(std::string(line.substr(0, eq))), line.remove_prefix(eq);
      ini.append(line);
      ini += '\n';
    }
    p = q < e ? q : std::string_view::npos;
  }
  return ini;
}

std::size_t complete_config_block(std::string& gcode, const PrintConfig& c) {
  std::string_view end = "; prusaslicer_config = end";
  std::size_t e = gcode.rfind(end);
  if (e == std::string::npos) end = "; CONFIG_BLOCK_END", e = gcode.rfind(end);
  if (e == std::string::npos || (e > 0 && gcode[e - 1] != '\n')) return 0;
  const std::string block = gcode_config_block(gcode);
  if (block.empty()) return 0;
  auto has = [&](const std::string& key) {
    for (std::size_t at = block.find(key + " ="); at != std::string::npos;
         at = block.find(key + " =", at + 1))
      if (at == 0 || block[at - 1] == '\n') return true;
    return false;
  };
  std::string add;
  std::size_t n = 0;
  for (const auto& [key, value] : c.profile)  // a std::map: in key order, as the block's
    if (read_by_print_stats(key) && !has(key)) add += "; " + key + " = " + value + "\n", ++n;
  gcode.insert(e, add);
  return n;
}

}  // namespace nonplanar
