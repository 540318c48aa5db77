// `slice --timings`: wall time per pipeline stage, read from the stages' progress reports (a
// stage reports 0 when it starts; context.hpp). A span runs from a stage's first report to the
// next report of another stage, so a retry shows as the same stages again, in order. Beside the
// wall time, the process's CPU time over the span (all threads): "cores" is their ratio, so
// a stage that leaves the second core idle shows 1.0 or less. "rss MB" is the process's
// resident size when the span ends, "peak MB" its high-water mark so far (Linux: VmRSS and
// VmHWM): the span where the peak rises is the stage that raised it. (Not reset per span
// through /proc/self/clear_refs: that would also reset what getrusage, and so /usr/bin/time,
// reports as the run's peak.)
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "nonplanar/context.hpp"

namespace nonplanar::cli {

class StageTimer {
 public:
  /// Records every report that goes through `ctx` (and still passes it on).
  void attach(Context& ctx);
  /// Ends the current span and starts `stage` (for work outside the library: "write").
  void mark(const std::string& stage);
  /// The spans in order, then the totals per stage and the run's wall time, on `out`.
  void print(std::FILE* out);

 private:
  using Clock = std::chrono::steady_clock;
  struct Span {
    std::string stage;
    double seconds = 0, cpu = 0;
    double rss_mb = 0, peak_mb = 0;  ///< at the span's end (0: unknown)
  };
  static double cpu_now();
  /// The process's resident size and its high-water mark, MB (0 where /proc cannot tell).
  static std::pair<double, double> memory_mb();
  /// Adds the wall and CPU time since the last report to the current span (if any).
  void close_span();
  void report(std::string_view stage);
  Clock::time_point start_ = Clock::now(), last_ = start_;
  double last_cpu_ = cpu_now();
  std::vector<Span> spans_;
};

}  // namespace nonplanar::cli
