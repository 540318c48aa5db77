#include "core/file_bytes.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace nonplanar::core {

FileBytes& FileBytes::operator=(FileBytes&& o) noexcept {
  if (this != &o) {
    this->~FileBytes();
    data_ = o.data_;
    size_ = o.size_;
    o.data_ = nullptr;
  }
  return *this;
}

FileBytes::~FileBytes() {
  if (data_) ::munmap(const_cast<void*>(data_), size_);
}

Expected<FileBytes> read_file_bytes(const std::filesystem::path& file, std::size_t max_bytes) {
  // O_NONBLOCK: opening a FIFO otherwise waits for a writer, forever (hostile input #21.20);
  // it changes nothing for a regular file, and anything else is refused below.
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0)
    return Error{Status::io_error, errno == ENOENT
                                       ? std::string("file not found")
                                       : std::string("cannot open: ") + std::strerror(errno)};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Error{Status::io_error,
                 S_ISDIR(st.st_mode)
                     ? "is a folder, not a file"
                     : "not a regular file (a pipe or a device cannot be read as a model)"};
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size > max_bytes) {
    ::close(fd);
    return Error{Status::invalid_mesh, "file is " + std::to_string(size) +
                                           " bytes, over the limit of " +
                                           std::to_string(max_bytes)};
  }
  if (size == 0) {
    ::close(fd);
    return FileBytes();
  }
  void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED)
    return Error{Status::io_error, std::string("cannot read: ") + std::strerror(errno)};
  return FileBytes(p, size);
}

}  // namespace nonplanar::core
