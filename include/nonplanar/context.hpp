// Progress reporting and cancellation, passed to every pipeline stage.
#pragma once

#include <atomic>
#include <functional>
#include <string_view>

namespace nonplanar {

/// Carried through every stage: where progress goes and whether to stop early.
/// A default-constructed Context reports nothing and never cancels.
struct Context {
  /// Called with a stage name and a fraction in [0, 1]; may be empty. A stage reports 0 when
  /// it starts, so the reports also mark where each stage's time begins (slice --timings).
  /// Reports come from the calling thread, one at a time.
  std::function<void(std::string_view stage, double fraction)> on_progress;
  /// When non-null and set, stages stop at their next check and return Status::cancelled.
  const std::atomic<bool>* cancel_flag = nullptr;

  bool cancelled() const { return cancel_flag && cancel_flag->load(std::memory_order_relaxed); }
  void progress(std::string_view stage, double fraction) const {
    if (on_progress) on_progress(stage, fraction);
  }
};

}  // namespace nonplanar
