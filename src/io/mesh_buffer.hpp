// Helpers shared by the mesh parsers: reading a whole file, face index checks (the
// tokenizer and strict number parsing: core/text_tokens.hpp). Parsers take the bytes in memory so
// they can be fuzzed directly.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "core/text_tokens.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar::io {

/// A whole file, memory-mapped read-only (no copy); unmapped on destruction.
class FileBytes {
 public:
  FileBytes() = default;
  FileBytes(const void* data, std::size_t size) : data_(data), size_(size) {}
  FileBytes(FileBytes&& o) noexcept : data_(o.data_), size_(o.size_) { o.data_ = nullptr; }
  FileBytes& operator=(FileBytes&& o) noexcept;
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  ~FileBytes();
  std::string_view view() const {
    return data_ ? std::string_view(static_cast<const char*>(data_), size_) : std::string_view();
  }

 private:
  const void* data_ = nullptr;
  std::size_t size_ = 0;
};

/// Whole file into memory. Errors: missing file, unreadable, a folder, larger than max_bytes.
Expected<FileBytes> read_file_bytes(const std::filesystem::path& file, std::size_t max_bytes);

// The tokenizer and number parsing live in core/ (the G-code reader uses them too).
using core::parse_double;
using core::parse_error_at;
using core::parse_int;
using core::Tokenizer;

/// Checks that a triangle index list references existing vertices; returns an error naming
/// the first bad face otherwise.
std::optional<Error> check_face_indices(const TriangleMesh& mesh);

}  // namespace nonplanar::io
