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

// The ZIP64 extended-information field (tag 1) among an entry's extra fields: each of usize,
// csize and local that reads 0xffffffff takes its 8-byte value from it. False when one is
// marked but missing, or a value is beyond what this reader takes.
bool zip64_sizes(std::string_view extra, std::uint64_t* usize, std::uint64_t* csize,
                 std::uint64_t* local) {
  std::uint64_t* marked[3] = {usize, csize, local};
  std::size_t at = 0;
  std::string_view info;
  while (at + 4 <= extra.size()) {
    const std::uint32_t tag = u16(extra, at), len = u16(extra, at + 2);
    if (at + 4 + len > extra.size()) break;
    if (tag == 1) info = extra.substr(at + 4, len);
    at += 4 + len;
  }
  std::size_t next = 0;
  for (std::uint64_t* v : marked) {
    if (*v != 0xffffffff) continue;
    if (next + 8 > info.size()) return false;
    *v = u32(info, next) | (std::uint64_t(u32(info, next + 4)) << 32);
    next += 8;
  }
  return *usize <= kMaxEntry && *csize <= kMaxEntry;
}

// Every entry, uncompressed, in central-directory order; with `only`, that entry alone (the
// others are neither inflated nor counted). At most `max_total` bytes uncompressed.
std::optional<std::vector<Entry>> read_zip(std::string_view z, std::string_view only = {},
                                           std::size_t max_total = kMaxEntry) {
  if (z.size() < 22) return std::nullopt;
  std::size_t eocd = std::string_view::npos;
  for (std::size_t i = z.size() - 22 + 1; i-- > 0 && z.size() - i <= 65557;)
    if (u32(z, i) == 0x06054b50) {
      eocd = i;
      break;
    }
  if (eocd == std::string_view::npos) return std::nullopt;
  std::uint64_t count = u16(z, eocd + 10), cd = u32(z, eocd + 16);
  // ZIP64 (lib3mf's packages): the locator 20 bytes before points at the ZIP64 end record,
  // which holds the entry count and the central directory's offset.
  if (cd == 0xffffffff && eocd >= 20 && u32(z, eocd - 20) == 0x07064b50) {
    const std::uint64_t rec = u32(z, eocd - 12) | (std::uint64_t(u32(z, eocd - 8)) << 32);
    if (rec + 56 > z.size() || u32(z, static_cast<std::size_t>(rec)) != 0x06064b50)
      return std::nullopt;
    const auto r = static_cast<std::size_t>(rec);
    count = u32(z, r + 32) | (std::uint64_t(u32(z, r + 36)) << 32);
    cd = u32(z, r + 48) | (std::uint64_t(u32(z, r + 52)) << 32);
    if (count > 65535 || cd > z.size()) return std::nullopt;
  }
  std::vector<Entry> out;
  std::size_t p = static_cast<std::size_t>(cd), total = 0;
  for (std::uint64_t k = 0; k < count; ++k) {
    if (p + 46 > z.size() || u32(z, p) != 0x02014b50) return std::nullopt;
    const std::uint32_t flags = u16(z, p + 8), method = u16(z, p + 10);
    std::uint64_t csize = u32(z, p + 20), usize = u32(z, p + 24);
    const std::uint32_t n = u16(z, p + 28), e = u16(z, p + 30), c = u16(z, p + 32);
    std::uint64_t local = u32(z, p + 42);  // 64 bits: local + 30 must not wrap
    if (p + 46 + n + e > z.size() || (flags & 1)) return std::nullopt;
    // lib3mf writes every entry with a ZIP64 extra field: the sizes and offset marked
    // 0xffffffff are there, in this order.
    if (!zip64_sizes(z.substr(p + 46 + n, e), &usize, &csize, &local)) return std::nullopt;
    if (local + 30 > z.size() || u32(z, static_cast<std::size_t>(local)) != 0x04034b50)
      return std::nullopt;
    Entry entry{std::string(z.substr(p + 46, n)), {}};
    if (!only.empty() && entry.name != only) {
      p += 46 + n + e + c;
      continue;
    }
    const std::size_t data = static_cast<std::size_t>(local) + 30 +
                             u16(z, static_cast<std::size_t>(local) + 26) +
                             u16(z, static_cast<std::size_t>(local) + 28);
    if (data + csize > z.size() || (total += usize) > max_total) return std::nullopt;
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

std::optional<std::string> zip_entry(std::string_view zip, std::string_view name,
                                     std::size_t max_size) {
  if (!name.empty() && name[0] == '/') name.remove_prefix(1);
  if (name.empty()) return std::nullopt;
  auto entries = read_zip(zip, name, std::min(max_size, kMaxEntry));
  if (!entries) return std::nullopt;
  for (Entry& e : *entries)
    if (e.name == name) return std::move(e.data);
  return std::nullopt;
}

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
