// write_file_atomically (src/core/atomic_file.hpp) with two writes in progress at once, as a
// shell's two engine runs write their meshes: a signal's clean-up removes both temporaries.
#include <gtest/gtest.h>

#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

#include "core/atomic_file.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

TEST(AtomicFile, TwoWritesInProgressAreBothRemovedOnASignal) {
  const fs::path dir = test::temp_dir("atomic_two");
  std::mutex mu;
  std::condition_variable cv;
  int inside = 0;
  bool cleaned = false;
  // Each write waits, half-written, until both are under way and the clean-up has run.
  auto write = [&](std::ostream& out) {
    out << "half";
    std::unique_lock<std::mutex> lock(mu);
    ++inside;
    cv.notify_all();
    cv.wait(lock, [&] { return cleaned; });
    return true;
  };
  Expected<void> a, b;
  std::thread ta([&] { a = write_file_atomically(dir / "a.stl", write); });
  std::thread tb([&] { b = write_file_atomically(dir / "b.stl", write); });
  {
    std::unique_lock<std::mutex> lock(mu);
    cv.wait(lock, [&] { return inside == 2; });
    int temporaries = 0;
    for (const auto& f : fs::directory_iterator(dir)) temporaries += f.path().extension() == ".tmp";
    EXPECT_EQ(temporaries, 2);
    remove_pending_temporary_file();  // what the signal handler calls
    cleaned = true;
  }
  cv.notify_all();
  ta.join();
  tb.join();
  // Both temporaries were unlinked under their writers: neither rename finds its file, and
  // nothing is left, under either name.
  ASSERT_FALSE(a);
  ASSERT_FALSE(b);
  EXPECT_NE(a.error().message.find("cannot rename"), std::string::npos) << a.error().message;
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
}  // namespace nonplanar
