#include "stage_timer.hpp"

#include <time.h>

#include <algorithm>
#include <map>
#include <tuple>

namespace nonplanar::cli {

void StageTimer::attach(Context& ctx) {
  auto next = std::move(ctx.on_progress);
  ctx.on_progress = [this, next](std::string_view stage, double f) {
    report(stage);
    if (next) next(stage, f);
  };
}

double StageTimer::cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::pair<double, double> StageTimer::memory_mb() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return {0, 0};
  char line[256];
  double hwm = 0, rss = 0;
  while (std::fgets(line, sizeof line, f)) {
    if (std::sscanf(line, "VmHWM: %lf kB", &hwm) == 1) continue;
    if (std::sscanf(line, "VmRSS: %lf kB", &rss) == 1) break;  // (it follows VmHWM)
  }
  std::fclose(f);
  return {rss / 1024, hwm / 1024};
}

void StageTimer::close_span() {
  const Clock::time_point now = Clock::now();
  const double cpu = cpu_now();
  if (!spans_.empty()) {
    Span& s = spans_.back();
    s.seconds += std::chrono::duration<double>(now - last_).count();
    s.cpu += cpu - last_cpu_;
    std::tie(s.rss_mb, s.peak_mb) = memory_mb();
  }
  last_ = now, last_cpu_ = cpu;
}

void StageTimer::report(std::string_view stage) {
  if (!spans_.empty() && spans_.back().stage == stage) return;
  close_span();
  spans_.push_back({std::string(stage), 0, 0});
}

void StageTimer::mark(const std::string& stage) {
  report(stage);
}

void StageTimer::print(std::FILE* out) {
  close_span();
  const double total = std::chrono::duration<double>(last_ - start_).count();
  std::fprintf(out, "timings (s):        wall      cpu  cores   rss MB  peak MB\n");
  std::map<std::string, std::pair<double, int>> sums;
  std::vector<std::string> order;
  double timed = 0, peak = 0;
  for (const Span& s : spans_) {
    std::fprintf(out, "  %-14s %8.3f %8.3f %6.2f %8.1f %8.1f\n", s.stage.c_str(), s.seconds, s.cpu,
                 s.seconds > 0 ? s.cpu / s.seconds : 0.0, s.rss_mb, s.peak_mb);
    timed += s.seconds, peak = std::max(peak, s.peak_mb);
    auto [it, fresh] = sums.try_emplace(s.stage, 0.0, 0);
    if (fresh) order.push_back(s.stage);
    it->second.first += s.seconds, ++it->second.second;
  }
  std::fprintf(out, "  per stage:");
  for (const std::string& s : order)
    std::fprintf(out, " %s %.3f%s", s.c_str(), sums[s].first,
                 sums[s].second > 1 ? (" (x" + std::to_string(sums[s].second) + ")").c_str() : "");
  // Before the first report: the command line and profiles.
  std::fprintf(out, "\n  setup %.3f, total %.3f (cpu %.3f), peak %.1f MB\n", total - timed, total,
               last_cpu_, peak);
}

}  // namespace nonplanar::cli
