// A whole file in memory (memory-mapped, read-only): the input of every parser.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string_view>

#include "nonplanar/status.hpp"

namespace nonplanar::core {

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

}  // namespace nonplanar::core
