// The settings PrusaSlicer appends to its G-code, read back as a profile.
#include "nonplanar/config.hpp"

namespace nonplanar {

std::string gcode_config_block(std::string_view gcode) {
  constexpr std::string_view kBegin = "; prusaslicer_config = begin";
  constexpr std::string_view kEnd = "; prusaslicer_config = end";
  // It is the file's last part: search from the end, so a long file costs nothing more.
  const std::size_t b = gcode.rfind(kBegin);
  if (b == std::string_view::npos || (b > 0 && gcode[b - 1] != '\n')) return {};
  const std::size_t e = gcode.find(kEnd, b);
  if (e == std::string_view::npos) return {};
  std::string ini;
  for (std::size_t p = gcode.find('\n', b); p != std::string_view::npos && p < e;) {
    const std::size_t q = std::min(gcode.find('\n', p + 1), e);
    std::string_view line = gcode.substr(p + 1, q - p - 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.rfind("; ", 0) == 0) {
      ini.append(line.substr(2));
      ini += '\n';
    }
    p = q < e ? q : std::string_view::npos;
  }
  return ini;
}

}  // namespace nonplanar
