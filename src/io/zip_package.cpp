// A minimal zip reader and writer (PKWARE APPNOTE: the end of central directory, central
// directory entries, local headers; stored and deflated entries) for zip_package.hpp.
#include "io/zip_package.hpp"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>

namespace nonplanar::io {
namespace {

struct Entry {
  std::string name, data;  // data uncompressed
};

std::uint32_t u16(std::string_view s, std::size_t at) {
  return static_cast<std::uint8_t>(s[at]) | static_cast<std::uint8_t>(s[at + 1]) << 8;
}
std::uint32_t u32(std::string_view s, std::size_t at) {
  return u16(s, at) | u16(s, at + 2) << 16;
}
void put16(std::string& s, std::uint32_t v) {
  s += static_cast<char>(v & 0xff), s += static_cast<char>(v >> 8 & 0xff);
}
void put32(std::string& s, std::uint32_t v) {
  put16(s, v & 0xffff), put16(s, v >> 16);
}

constexpr std::size_t kMaxEntry = std::size_t(1) << 30;

std::optional<std::string> inflate_raw(std::string_view in, std::size_t size) {
  // Deflate expands at most 1032:1: a larger claim is a lie, not worth the memory.
  if (size > kMaxEntry || size > 1032 * in.size() + 64) return std::nullopt;
  std::string out(size, '\0');
  z_stream z{};
  if (inflateInit2(&z, -MAX_WBITS) != Z_OK) return std::nullopt;
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = inflate(&z, Z_FINISH);
  const bool ok = rc == Z_STREAM_END && z.total_out == size;
  inflateEnd(&z);
  if (!ok) return std::nullopt;
  return out;
}

// Every entry, uncompressed, in central-directory order.
std::optional<std::vector<Entry>> read_zip(std::string_view z) {
  if (z.size() < 22) return std::nullopt;
  std::size_t eocd = std::string_view::npos;
  for (std::size_t i = z.size() - 22 + 1; i-- > 0 && z.size() - i <= 65557;)
    if (u32(z, i) == 0x06054b50) {
      eocd = i;
      break;
    }
  if (eocd == std::string_view::npos) return std::nullopt;
  const std::uint32_t count = u16(z, eocd + 10), cd = u32(z, eocd + 16);
  std::vector<Entry> out;
  std::size_t p = cd, total = 0;
  for (std::uint32_t k = 0; k < count; ++k) {
    if (p + 46 > z.size() || u32(z, p) != 0x02014b50) return std::nullopt;
    const std::uint32_t flags = u16(z, p + 8), method = u16(z, p + 10);
    const std::uint32_t csize = u32(z, p + 20), usize = u32(z, p + 24);
    const std::uint32_t n = u16(z, p + 28), e = u16(z, p + 30), c = u16(z, p + 32);
    const std::size_t local = u32(z, p + 42);  // size_t: local + 30 must not wrap
    if (p + 46 + n > z.size() || (flags & 1) || csize == 0xffffffff || local + 30 > z.size() ||
        u32(z, local) != 0x04034b50)
      return std::nullopt;
    Entry entry{std::string(z.substr(p + 46, n)), {}};
    const std::size_t data = local + 30 + u16(z, local + 26) + u16(z, local + 28);
    if (data + csize > z.size() || (total += usize) > kMaxEntry) return std::nullopt;
    const std::string_view raw = z.substr(data, csize);
    if (method == 0 && csize == usize) {
      entry.data = std::string(raw);
    } else if (method == 8) {
      auto inflated = inflate_raw(raw, usize);
      if (!inflated) return std::nullopt;
      entry.data = std::move(*inflated);
    } else {
      return std::nullopt;
    }
    out.push_back(std::move(entry));
    p += 46 + n + e + c;
  }
  return out;
}

std::string write_zip(const std::vector<Entry>& entries) {
  std::string out, cd;
  for (const Entry& e : entries) {
    const auto crc = static_cast<std::uint32_t>(
        crc32(0, reinterpret_cast<const Bytef*>(e.data.data()), static_cast<uInt>(e.data.size())));
    const auto size = static_cast<std::uint32_t>(e.data.size());
    const auto at = static_cast<std::uint32_t>(out.size());
    const auto n = static_cast<std::uint32_t>(e.name.size());
    put32(out, 0x04034b50), put16(out, 20), put16(out, 0), put16(out, 0), put16(out, 0);
    put16(out, 0x21), put32(out, crc), put32(out, size), put32(out, size), put16(out, n);
    put16(out, 0);
    out += e.name, out += e.data;
    put32(cd, 0x02014b50), put16(cd, 20), put16(cd, 20), put16(cd, 0), put16(cd, 0);
    put16(cd, 0), put16(cd, 0x21), put32(cd, crc), put32(cd, size), put32(cd, size);
    put16(cd, n), put16(cd, 0), put16(cd, 0), put16(cd, 0), put16(cd, 0), put32(cd, 0);
    put32(cd, at), cd += e.name;
  }
  const auto cd_at = static_cast<std::uint32_t>(out.size());
  out += cd;
  put32(out, 0x06054b50), put16(out, 0), put16(out, 0);
  put16(out, static_cast<std::uint32_t>(entries.size()));
  put16(out, static_cast<std::uint32_t>(entries.size()));
  put32(out, static_cast<std::uint32_t>(cd.size())), put32(out, cd_at), put16(out, 0);
  return out;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The part a relationship in `rels` (e.g. "3D/_rels/3dmodel.model.rels") points to.
std::string target_part(const std::string& rels, std::string target) {
  if (!target.empty() && target[0] == '/') return target.substr(1);
  const std::size_t r = rels.rfind("_rels/");
  return (r == std::string::npos ? "" : rels.substr(0, r)) + target;
}

// rels with the <Relationship …/> elements whose target is not a part removed.
std::string prune(const std::string& rels_name, const std::string& xml,
                  const std::vector<std::string>& parts, std::vector<std::string>& dropped) {
  std::string out;
  std::size_t p = 0;
  for (std::size_t a; (a = xml.find("<Relationship ", p)) != std::string::npos;) {
    const std::size_t e = xml.find('>', a);
    if (e == std::string::npos) break;
    std::size_t end = e + 1;
    if (xml[e - 1] != '/') {  // <Relationship …></Relationship>
      const std::size_t close = xml.find("</Relationship>", e);
      if (close == std::string::npos) break;
      end = close + 15;
    }
    const std::string element = xml.substr(a, end - a);
    const std::size_t t = element.find("Target=\"");
    bool keep = true;
    if (t != std::string::npos) {
      const std::size_t q = element.find('"', t + 8);
      const std::string target = element.substr(t + 8, q - t - 8);
      const bool external = element.find("TargetMode=\"External\"") != std::string::npos;
      const std::string part = lower(target_part(rels_name, target));
      keep = external || std::find(parts.begin(), parts.end(), part) != parts.end();
      if (!keep) dropped.push_back(target);
    }
    out += xml.substr(p, a - p);
    if (keep) out += element;
    p = end;
  }
  return out + xml.substr(p);
}

}  // namespace

std::optional<std::string> drop_dangling_relationships(std::string_view zip,
                                                       std::vector<std::string>* dropped) {
  auto entries = read_zip(zip);
  if (!entries) return std::nullopt;
  std::vector<std::string> parts, gone;
  for (const Entry& e : *entries) parts.push_back(lower(e.name));
  for (Entry& e : *entries)
    if (e.name.size() > 5 && lower(e.name).compare(e.name.size() - 5, 5, ".rels") == 0)
      e.data = prune(e.name, e.data, parts, gone);
  if (gone.empty()) return std::nullopt;
  if (dropped) *dropped = gone;
  return write_zip(*entries);
}

}  // namespace nonplanar::io
