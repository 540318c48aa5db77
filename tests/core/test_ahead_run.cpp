// core::AheadRun: a stage started before it is known to be needed, at the caller's priority or
// taking only the cores other work leaves.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/ahead_run.hpp"
#include "core/parallel.hpp"

namespace nonplanar {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Until cancelled, at most 20 s (a test that fails rather than hangs); the seconds it waited.
double wait_for_cancel(const Context& c) {
  const auto start = Clock::now();
  while (!c.cancelled() && Clock::now() - start < 20s) std::this_thread::sleep_for(1ms);
  return std::chrono::duration<double>(Clock::now() - start).count();
}

TEST(AheadRun, ItsProgressReachesTheCallerInOrderOnTheCallersThread) {
  std::vector<std::string> seen;
  std::vector<std::thread::id> threads;
  Context outer;
  outer.on_progress = [&](std::string_view stage, double f) {
    seen.push_back(std::string(stage) + " " + std::to_string(static_cast<int>(f * 100)));
    threads.push_back(std::this_thread::get_id());
  };
  core::AheadRun<int> run(outer, [](const Context& c) {
    c.progress("engine", 0);
    std::this_thread::sleep_for(30ms);
    c.progress("engine", 0.5);
    c.progress("map back", 0);
    return 42;
  });
  std::this_thread::sleep_for(60ms);
  EXPECT_TRUE(seen.empty());  // nothing reaches the caller until it waits
  EXPECT_TRUE(run.running());
  EXPECT_EQ(run.get(), 42);
  EXPECT_FALSE(run.running());
  EXPECT_EQ(seen, (std::vector<std::string>{"engine 0", "engine 50", "map back 0"}));
  for (const auto& id : threads) EXPECT_EQ(id, std::this_thread::get_id());
}

TEST(AheadRun, DropStopsItAndWaits) {
  std::atomic<double> waited{-1};
  {
    core::AheadRun<int> run(Context{}, [&](const Context& c) {
      waited = wait_for_cancel(c);
      return 1;
    });
    std::this_thread::sleep_for(20ms);
    run.drop();
    EXPECT_GE(waited.load(), 0.0);  // done when drop() returns
    EXPECT_FALSE(run.running());
  }
  EXPECT_LT(waited.load(), 10.0);
  // Dropped by going out of scope too, and what it threw is dropped with it.
  const auto start = Clock::now();
  {
    core::AheadRun<int> run(Context{}, [](const Context& c) -> int {
      wait_for_cancel(c);
      throw std::runtime_error("stopped");
    });
  }
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 10.0);
}

TEST(AheadRun, TheCallersCancellationReachesItWhileTheCallerWaits) {
  std::atomic<bool> flag{false};
  Context outer;
  outer.cancel_flag = &flag;
  core::AheadRun<double> run(outer, [](const Context& c) { return wait_for_cancel(c); });
  std::thread ctrl_c([&] {
    std::this_thread::sleep_for(50ms);
    flag = true;
  });
  const double waited = run.get();
  ctrl_c.join();
  EXPECT_GE(waited, 0.04);
  EXPECT_LT(waited, 10.0);
}

TEST(AheadRun, GetRethrowsWhatItThrew) {
  core::AheadRun<int> run(Context{}, [](const Context&) -> int { throw std::bad_alloc(); });
  EXPECT_THROW(run.get(), std::bad_alloc);
}

TEST(AheadRun, AtIdlePriorityItRunsAtNice19OnOneThreadAndLeavesTheCallersAlone) {
  auto tid = [] { return static_cast<id_t>(::syscall(SYS_gettid)); };
  const int mine = ::getpriority(PRIO_PROCESS, tid());
  std::atomic<int> others{0};
  std::thread::id ran_on;
  core::AheadRun<int> run(
      Context{},
      [&](const Context&) {
        ran_on = std::this_thread::get_id();
        // Its loops stay on its own thread (a worker would run at the caller's priority).
        core::parallel_for(0, 64, [&](int) {
          if (std::this_thread::get_id() != ran_on) ++others;
        });
        return ::getpriority(PRIO_PROCESS, tid());
      },
      core::Priority::idle);
  while (!run.ready()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_EQ(run.get(), 19);
  EXPECT_NE(ran_on, std::this_thread::get_id());
#ifndef NONPLANAR_TSAN
  EXPECT_EQ(others.load(), 0);
#endif
  EXPECT_EQ(::getpriority(PRIO_PROCESS, tid()), mine);
}

}  // namespace
}  // namespace nonplanar
