#include "core/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <system_error>

namespace nonplanar {
namespace {
// The temporaries being written, for remove_pending_temporary_file(): a few slots (a shell's
// two engine runs write their meshes side by side), each a fixed buffer published through an
// atomic state, because a signal handler may read them at any moment.
constexpr int kPendingSlots = 4;
enum : int { kFree = 0, kFilling = 1, kSet = 2 };
char g_pending[kPendingSlots][4096];
std::atomic<int> g_pending_state[kPendingSlots]{};

struct PendingGuard {
  explicit PendingGuard(const std::string& path) {
    if (path.size() >= sizeof g_pending[0]) return;  // too long to register: not removable early
    for (int i = 0; i < kPendingSlots && slot_ < 0; ++i)
      if (int none = kFree; g_pending_state[i].compare_exchange_strong(none, kFilling)) slot_ = i;
    if (slot_ < 0) return;  // every slot taken: not removable early
    std::memcpy(g_pending[slot_], path.c_str(), path.size() + 1);
    g_pending_state[slot_].store(kSet);
  }
  ~PendingGuard() {
    if (slot_ >= 0) g_pending_state[slot_].store(kFree);
  }
  PendingGuard(const PendingGuard&) = delete;
  PendingGuard& operator=(const PendingGuard&) = delete;

 private:
  int slot_ = -1;
};

// Temporaries are ".nonplanar-PID-XXXXXX.tmp": short whatever the output's name (a 255-byte
// name must still work), and a later run can tell whose they are.
constexpr char kPrefix[] = ".nonplanar-";
constexpr char kSuffix[] = ".tmp";

// Removes temporaries in `dir` left by runs that no longer exist (killed mid-write).
void remove_stale_temporaries(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    constexpr std::size_t n_suffix = sizeof kSuffix - 1;
    if (name.rfind(kPrefix, 0) != 0 || name.size() < n_suffix ||
        name.compare(name.size() - n_suffix, n_suffix, kSuffix) != 0)
      continue;
    const std::string rest = name.substr(sizeof kPrefix - 1);
    char* end_pid = nullptr;
    const long pid = std::strtol(rest.c_str(), &end_pid, 10);
    if (pid <= 0 || end_pid == rest.c_str() || *end_pid != '-') continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // still running
    std::error_code rm;
    fs::remove(it->path(), rm);
  }
}

// Writes straight into what `file` is when it is not a regular file (a device such as
// /dev/null or /dev/stdout, a pipe): renaming over it would replace the device node.
Expected<void> write_in_place(const std::filesystem::path& file,
                              const std::function<bool(std::ostream&)>& write) {
  std::ofstream out(file, std::ios::binary);
  if (!out)
    return Error{Status::io_error, file.string() + ": cannot write: " + std::strerror(errno)};
  errno = 0;
  const bool ok = write(out) && out.flush().good();
  if (!ok)
    return Error{Status::io_error, file.string() + ": write failed" +
                                       (errno ? std::string(": ") + std::strerror(errno) : "")};
  return {};
}
}  // namespace

void remove_pending_temporary_file() {
  for (int i = 0; i < kPendingSlots; ++i)
    if (g_pending_state[i].load() == kSet) ::unlink(g_pending[i]);
}

Expected<void> write_file_atomically(const std::filesystem::path& file_in,
                                     const std::function<bool(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // A link is written through: the file it names is replaced, the link stays.
  fs::path file = file_in;
  if (fs::is_symlink(fs::symlink_status(file, ec))) {
    const fs::path target = fs::weakly_canonical(file, ec);
    if (!ec) file = target;
  }
  const fs::file_status st = fs::status(file, ec);
  if (fs::exists(st)) {
    if (fs::is_directory(st)) return Error{Status::io_error, file_in.string() + ": is a folder"};
    if (fs::is_character_file(st) || fs::is_fifo(st)) return write_in_place(file, write);
    if (!fs::is_regular_file(st))
      return Error{Status::io_error, file_in.string() + ": not a regular file, not replaced"};
  }
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    return Error{Status::io_error, file_in.string() + ": folder does not exist"};
  remove_stale_temporaries(dir);
  // Hidden, unique temporary in the same folder so the rename is atomic (same filesystem).
  std::random_device rd;
  char name[64];
  std::snprintf(name, sizeof name, "%s%ld-%06x%s", kPrefix, static_cast<long>(::getpid()),
                static_cast<unsigned>(rd() & 0xffffff), kSuffix);
  const fs::path tmp = dir / name;
  bool ok = false;
  int err = 0;
  const PendingGuard pending(tmp.string());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      return Error{Status::io_error, file_in.string() + ": cannot write in " + dir.string() + ": " +
                                         std::strerror(errno)};
    errno = 0;
    ok = write(out);
    out.flush();
    ok = ok && out.good();
    err = errno;
  }
  if (!ok) {
    fs::remove(tmp, ec);
    // A full disk says so (ENOSPC), naming the folder whose disk it is.
    return Error{
        Status::io_error,
        file_in.string() + ": write failed" +
            (err ? std::string(": ") + std::strerror(err) + " (in " + dir.string() + ")" : "")};
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp, ec);
    return Error{Status::io_error, file_in.string() + ": cannot rename temporary file: " + why};
  }
  return {};
}

}  // namespace nonplanar
