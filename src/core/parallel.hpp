// One way to spread a loop over the cores, for every stage: oneTBB in ordinary builds; plain
// std::threads in a ThreadSanitizer build (NONPLANAR_TSAN). Debian's libtbb is not built with
// -fsanitize=thread, so TSan cannot see the synchronisation of TBB's scheduler and reports
// races inside it; the loop bodies, which are ours, are what must be race-free, and with
// std::thread TSan checks exactly them. Bodies must not depend on which thread runs them or
// in which order (results never depend on the thread count).
#pragma once

#include <algorithm>
#include <cstddef>
#include <utility>

#ifdef NONPLANAR_TSAN
#include <future>
#include <thread>
#include <vector>
#else
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#endif

namespace nonplanar::core {

#ifdef NONPLANAR_TSAN
namespace detail {
// Splits [begin, end) into one block per thread (at least 2, so TSan sees two threads).
template <class Index, class F>
void on_threads(Index begin, Index end, F&& block) {
  if (end <= begin) return;
  const auto n = static_cast<std::size_t>(end - begin);
  const std::size_t k = std::min<std::size_t>(n, std::max(2u, std::thread::hardware_concurrency()));
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < k; ++t) {
    const Index lo = begin + static_cast<Index>(n * t / k);
    const Index hi = begin + static_cast<Index>(n * (t + 1) / k);
    threads.emplace_back([&block, lo, hi] { block(lo, hi); });
  }
  for (std::thread& th : threads) th.join();
}
}  // namespace detail
#endif

/// f(i) for every i in [begin, end), in parallel.
template <class Index, class F>
void parallel_for(Index begin, Index end, F&& f) {
#ifdef NONPLANAR_TSAN
  detail::on_threads(begin, end, [&f](Index lo, Index hi) {
    for (Index i = lo; i < hi; ++i) f(i);
  });
#else
  tbb::parallel_for(begin, end, std::forward<F>(f));
#endif
}

/// f(lo, hi) for blocks [lo, hi) that tile [begin, end), of about `grain` indices (a body that
/// keeps per-block scratch space).
template <class Index, class F>
void parallel_blocks(Index begin, Index end, Index grain, F&& f) {
#ifdef NONPLANAR_TSAN
  (void)grain;
  detail::on_threads(begin, end, f);
#else
  tbb::parallel_for(tbb::blocked_range<Index>(begin, end, grain),
                    [&f](const tbb::blocked_range<Index>& r) { f(r.begin(), r.end()); });
#endif
}

/// A task run beside the caller, waited for on every way out (before the object goes).
class Background {
 public:
  Background() = default;
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;
  /// Waits too; what the task threw is then dropped (a destructor must not throw, and on the
  /// way out of an error the caller's own exception is the one that counts): call wait() to
  /// have it.
  ~Background() {
    try {
      wait();
    } catch (...) {
    }
  }
  template <class F>
  void run(F&& f) {
#ifdef NONPLANAR_TSAN
    tasks_.push_back(std::async(std::launch::async, std::forward<F>(f)));
#else
    group_.run(std::forward<F>(f));
#endif
  }
  /// Waits for the tasks; rethrows what one threw (std::bad_alloc under --max-memory).
  void wait() {
#ifdef NONPLANAR_TSAN
    std::vector<std::future<void>> tasks = std::move(tasks_);
    tasks_.clear();
    for (auto& t : tasks) t.wait();
    for (auto& t : tasks) t.get();
#else
    group_.wait();
#endif
  }

 private:
#ifdef NONPLANAR_TSAN
  std::vector<std::future<void>> tasks_;
#else
  tbb::task_group group_;
#endif
};

}  // namespace nonplanar::core
