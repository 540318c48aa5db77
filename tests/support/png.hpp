// Reading a screenshot back: a PNG decoder for what headless Chromium writes (8-bit RGB or
// RGBA, not interlaced), so a test can count what was drawn.
#pragma once

#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace nonplanar::test {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 bytes per pixel, rows top to bottom
};

/// The image, or width 0 when the bytes are not a PNG this reads.
inline Image decode_png(const std::string& png) {
  auto u32 = [&](std::size_t at) {
    return std::uint32_t(std::uint8_t(png[at])) << 24 |
           std::uint32_t(std::uint8_t(png[at + 1])) << 16 |
           std::uint32_t(std::uint8_t(png[at + 2])) << 8 | std::uint32_t(std::uint8_t(png[at + 3]));
  };
  Image img;
  if (png.size() < 33 || png.compare(1, 3, "PNG") != 0) return img;
  std::string idat;
  int channels = 0;
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const std::uint32_t len = u32(at);
    const std::string type = png.substr(at + 4, 4);
    if (at + 12 + len > png.size()) return {};
    if (type == "IHDR") {
      img.width = static_cast<int>(u32(at + 8));
      img.height = static_cast<int>(u32(at + 12));
      const int depth = png[at + 16], color = png[at + 17], interlace = png[at + 20];
      channels = color == 2 ? 3 : color == 6 ? 4 : 0;
      if (depth != 8 || channels == 0 || interlace != 0) return {};
    } else if (type == "IDAT") {
      idat.append(png, at + 8, len);
    }
    at += 12 + len;
  }
  const std::size_t stride = static_cast<std::size_t>(img.width) * channels;
  std::vector<std::uint8_t> raw((stride + 1) * static_cast<std::size_t>(img.height));
  uLongf size = raw.size();
  if (img.width <= 0 ||
      uncompress(raw.data(), &size, reinterpret_cast<const Bytef*>(idat.data()), idat.size()) !=
          Z_OK ||
      size != raw.size())
    return {};
  // Undo each row's filter (PNG spec §9) in place.
  std::vector<std::uint8_t> prev(stride, 0);
  img.rgb.reserve(static_cast<std::size_t>(img.width) * img.height * 3);
  for (int y = 0; y < img.height; ++y) {
    std::uint8_t* row = &raw[y * (stride + 1) + 1];
    const int filter = row[-1];
    for (std::size_t i = 0; i < stride; ++i) {
      const int a = i >= static_cast<std::size_t>(channels) ? row[i - channels] : 0;
      const int b = prev[i], c = i >= static_cast<std::size_t>(channels) ? prev[i - channels] : 0;
      int p = row[i];
      if (filter == 1)
        p += a;
      else if (filter == 2)
        p += b;
      else if (filter == 3)
        p += (a + b) / 2;
      else if (filter == 4) {
        const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
        p += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      row[i] = static_cast<std::uint8_t>(p);
    }
    for (int x = 0; x < img.width; ++x)
      for (int k = 0; k < 3; ++k) img.rgb.push_back(row[x * channels + k]);
    prev.assign(row, row + stride);
  }
  return img;
}

}  // namespace nonplanar::test
