#include "core/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <system_error>

namespace nonplanar {

Expected<bool> write_file_atomically(const std::filesystem::path& file,
                                     const std::function<bool(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return Error{Status::io_error, file.string() + ": folder does not exist"};
  // Hidden, unique temporary in the same folder so the rename is atomic (same filesystem).
  std::random_device rd;
  const fs::path tmp = dir / ("." + file.filename().string() + ".tmp" + std::to_string(::getpid()) +
                              "_" + std::to_string(rd() & 0xffffff));
  bool ok = false;
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      return Error{Status::io_error, file.string() + ": cannot write: " + std::strerror(errno)};
    ok = write(out);
    out.flush();
    ok = ok && out.good();
  }
  if (!ok) {
    fs::remove(tmp, ec);
    return Error{Status::io_error, file.string() + ": write failed"};
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return Error{Status::io_error,
                 file.string() + ": cannot rename temporary file: " + ec.message()};
  }
  return true;
}

}  // namespace nonplanar
