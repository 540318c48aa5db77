// A stage started ahead of knowing it is needed, on a thread of its own, so that its time
// overlaps the caller's work that decides whether it is.
#pragma once

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <future>
#include <mutex>
#include <string>
#include <utility>

#ifndef NONPLANAR_TSAN
#include <tbb/task_arena.h>
#endif

#include "nonplanar/context.hpp"

namespace nonplanar::core {

/// How an AheadRun's thread competes for the cores: as the caller's (it mostly waits for
/// another program), or with what is left of them: nice 19 and its loops on its own thread
/// (work needed only once another program's run is done, that should not slow that run).
enum class Priority { normal, idle };

/// Runs f(const Context&) -> T beside the caller. Its progress reports wait in a queue until the
/// caller takes the result (get(), which passes them on to the caller's context from the
/// caller's thread, as Context asks); the caller's cancellation reaches it then too, and drop()
/// stops it (its stages return cancelled) and waits. Waited for on every way out.
template <class T>
class AheadRun {
 public:
  template <class F>
  AheadRun(const Context& outer, F&& f, Priority priority = Priority::normal) : outer_(outer) {
    inner_.cancel_flag = &stop_;
    inner_.on_progress = [this](std::string_view stage, double fraction) {
      const std::lock_guard<std::mutex> lock(m_);
      reports_.emplace_back(std::string(stage), fraction);
    };
    result_ = std::async(std::launch::async, [this, priority, g = std::forward<F>(f)]() mutable {
      if (priority == Priority::normal) return g(inner_);
      // Linux: a thread's nice value is its own (PRIO_PROCESS of its thread id), and goes
      // with it.
      (void)::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 19);
#ifdef NONPLANAR_TSAN
      return g(inner_);
#else
      tbb::task_arena one(1);  // a worker would run its loops at the caller's priority
      return one.execute([&] { return g(inner_); });
#endif
    });
  }
  AheadRun(const AheadRun&) = delete;
  AheadRun& operator=(const AheadRun&) = delete;
  ~AheadRun() {
    drop();
  }

  /// Whether it has been neither taken nor dropped.
  bool running() const {
    return result_.valid();
  }
  /// Whether its result is there to take (get() then does not wait).
  bool ready() const {
    return result_.valid() &&
           result_.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  }

  /// Waits for the result, passing its progress on as it comes (and the caller's cancellation
  /// to it); rethrows what it threw.
  T get() {
    using namespace std::chrono_literals;
    while (result_.wait_for(20ms) != std::future_status::ready) {
      relay();
      if (outer_.cancelled()) stop_ = true;
    }
    relay();
    return result_.get();
  }

  /// Stops it and waits; its result and what it threw are dropped.
  void drop() {
    if (!result_.valid()) return;
    stop_ = true;
    result_.wait();
    try {
      (void)result_.get();
    } catch (...) {
    }
  }

 private:
  void relay() {
    std::deque<std::pair<std::string, double>> reports;
    {
      const std::lock_guard<std::mutex> lock(m_);
      reports.swap(reports_);
    }
    for (const auto& [stage, fraction] : reports) outer_.progress(stage, fraction);
  }

  const Context& outer_;
  Context inner_;
  std::atomic<bool> stop_{false};
  std::mutex m_;
  std::deque<std::pair<std::string, double>> reports_;
  std::future<T> result_;
};

}  // namespace nonplanar::core
