#include "core/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <system_error>

namespace nonplanar {
namespace {
// The temporary being written, for remove_pending_temporary_file(). A fixed buffer, published
// through an atomic flag, because a signal handler may read it at any moment.
char g_pending[4096];
std::atomic<bool> g_pending_set{false};

struct PendingGuard {
  explicit PendingGuard(const std::string& path) {
    if (path.size() >= sizeof g_pending) return;  // too long to register: not removable early
    std::memcpy(g_pending, path.c_str(), path.size() + 1);
    g_pending_set.store(true);
  }
  ~PendingGuard() { g_pending_set.store(false); }
  PendingGuard(const PendingGuard&) = delete;
  PendingGuard& operator=(const PendingGuard&) = delete;
};
}  // namespace

void remove_pending_temporary_file() {
  if (g_pending_set.load()) ::unlink(g_pending);
}

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
  const PendingGuard pending(tmp.string());
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
