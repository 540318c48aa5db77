// Helpers shared by the mesh parsers: reading a whole file, a line-aware tokenizer and
// strict number parsing. Parsers take the bytes in memory so they can be fuzzed directly.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

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

/// Parse a whole token as a finite double ("1e3", "-0.5"); nullopt for anything else,
/// including "nan", "inf" and trailing garbage.
std::optional<double> parse_double(std::string_view token);
/// Parse a whole token as a long long; nullopt on garbage or overflow.
std::optional<long long> parse_int(std::string_view token);

/// Splits text into whitespace-separated tokens and counts lines (LF, CRLF and lone CR).
class Tokenizer {
 public:
  explicit Tokenizer(std::string_view text) : text_(text) {}
  /// Next token, or empty at the end. line() is the line of the returned token.
  std::string_view next();
  /// Skip to the start of the next line.
  void skip_line();
  /// The rest of the current line (without the line break), consuming it.
  std::string_view rest_of_line();
  bool at_end();
  int line() const { return line_; }

 private:
  void skip_space();
  std::string_view text_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

/// "line N: msg" — the parsers' error text, to be prefixed by the file name by the loader.
Error parse_error_at(int line, const std::string& msg);

/// Checks that a triangle index list references existing vertices; returns an error naming
/// the first bad face otherwise.
std::optional<Error> check_face_indices(const TriangleMesh& mesh);

}  // namespace nonplanar::io
