#include "core/base64.hpp"

#include <cstdint>

namespace nonplanar::core {

std::string base64_encode(std::string_view bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t m = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t w = 0;
    for (std::size_t k = 0; k < 3; ++k)
      w = (w << 8) | (k < m ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k)
      out += k <= m ? kBase64Alphabet[(w >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

}  // namespace nonplanar::core
