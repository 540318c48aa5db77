// Atomic file output: write to a temporary file beside the target, then rename over it,
// so a half-written file never exists under the final name.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>

#include "nonplanar/status.hpp"

namespace nonplanar {

/// Calls write(stream) on a temporary file in the target's folder, flushes it, and renames
/// it to `file`. On any failure (write returns false, I/O error) the temporary is removed
/// and an io_error "FILE: reason" is returned.
Expected<void> write_file_atomically(const std::filesystem::path& file,
                                     const std::function<bool(std::ostream&)>& write);

/// Removes the temporary files the write_file_atomically calls in progress are writing (up to
/// 4 at once are known), if any. Async-signal-safe (unlink only): for a signal handler that is
/// about to _exit.
void remove_pending_temporary_file();

}  // namespace nonplanar
