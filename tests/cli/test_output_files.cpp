// Where the CLI writes (issue 21): into a pipe or a link rather than over it, never over its
// input, to names as long as the filesystem allows, cleaning up after killed runs, and a
// failed stdout is an error, not a pass.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "support/cli.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;
using test::run_cli;

fs::path small_box(const fs::path& dir) {
  const fs::path p = dir / "box.stl";
  EXPECT_TRUE(write_stl(p, test::box({0, 0, 0}, {10, 10, 2})));
  return p;
}

TEST(OutputFiles, APipeIsWrittenIntoNotReplaced) {
  const fs::path dir = test::temp_dir("out_fifo");
  const fs::path model = small_box(dir), fifo = dir / "out.gcode";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Read without blocking, so that a writer that renamed over the pipe fails the test instead
  // of hanging it.
  std::string got;
  std::thread reader([&] {
    const int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    if (fd < 0) return;
    char buf[65536];
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (std::chrono::steady_clock::now() < end) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n > 0) got.append(buf, static_cast<std::size_t>(n));
      if (n == 0 && !got.empty()) break;  // the writer closed
      if (n <= 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ::close(fd);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the reader is open
  const auto r = run_cli("slice -q --planar " + model.string() + " -o " + fifo.string(), 120);
  reader.join();
  EXPECT_EQ(r.code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the pipe was replaced by a file";
  EXPECT_NE(got.find(";LAYER_CHANGE"), std::string::npos) << got.size() << " bytes read";
  EXPECT_NE(got.find("M84"), std::string::npos);  // all of it, to the end G-code
}

TEST(OutputFiles, ALinkIsWrittenThrough) {
  const fs::path dir = test::temp_dir("out_link");
  const fs::path model = small_box(dir);
  fs::create_directories(dir / "real");
  test::write_bytes(dir / "real" / "part.gcode", "old");
  fs::create_symlink(dir / "real" / "part.gcode", dir / "link.gcode");
  const auto r =
      run_cli("slice -q --planar " + model.string() + " -o " + (dir / "link.gcode").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir / "link.gcode"));
  EXPECT_NE(test::read_bytes(dir / "real" / "part.gcode").find(";LAYER_CHANGE"), std::string::npos);
}

TEST(OutputFiles, TheInputIsNeverOverwritten) {
  const fs::path dir = test::temp_dir("out_input");
  const fs::path model = small_box(dir);
  const std::string before = test::read_bytes(model);
  fs::create_symlink(model, dir / "alias.stl");
  const std::string other = (dir / "x.json").string();
  for (const std::string& args :
       {"slice -q " + model.string() + " -o " + model.string(),
        "slice -q " + model.string() + " -o " + (dir / "." / "box.stl").string(),
        "slice -q " + (dir / "alias.stl").string() + " -o " + model.string(),
        "fit -q " + model.string() + " --export-mesh " + model.string(),
        "analyze -q " + model.string() + " --export-patches " + model.string(),
        "layers -q " + model.string() + " --export-layers " + other + " --export-normalized " +
            model.string(),
        "fit -q " + model.string() + " --export-surfaces " + other + " --export-mesh " + other}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(test::count_lines(r.err), 1u) << args << "\n" << r.err;
    EXPECT_TRUE(r.err.find("would be overwritten") != std::string::npos ||
                r.err.find("cannot share a file") != std::string::npos)
        << r.err;
    EXPECT_EQ(test::read_bytes(model), before) << args;
    EXPECT_FALSE(fs::exists(other)) << args;
  }
}

TEST(OutputFiles, LongNamesAndStaleTemporaries) {
  const fs::path dir = test::temp_dir("out_long");
  const fs::path model = small_box(dir);
  // A run killed mid-write (a process that no longer exists) left its temporary.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);
  const fs::path stale = dir / (".nonplanar-" + std::to_string(child) + "-00beef.tmp");
  const fs::path alive = dir / (".nonplanar-" + std::to_string(::getpid()) + "-00cafe.tmp");
  test::write_bytes(stale, "half a file");
  test::write_bytes(alive, "being written");
  // 250 bytes: the longest name most filesystems allow is 255.
  const fs::path out = dir / (std::string(241, 'n') + ".gcode");
  ASSERT_EQ(out.filename().string().size(), 247u);
  const auto r = run_cli("slice -q --planar " + model.string() + " -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out));
  EXPECT_FALSE(fs::exists(stale)) << "a dead run's temporary was left";
  EXPECT_TRUE(fs::exists(alive)) << "a running writer's temporary was removed";
}

TEST(OutputFiles, AFullStdoutIsAnError) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const fs::path dir = test::temp_dir("out_full");
  const fs::path model = small_box(dir), g = dir / "p.gcode";
  ASSERT_EQ(run_cli("slice -q --planar " + model.string() + " -o " + g.string()).code, 0);
  for (const std::string& args : {"check --json " + g.string() + " --mesh " + model.string(),
                                  "analyze --json " + model.string()}) {
    const std::string cmd =
        std::string(NONPLANAR_CLI) + " " + args + " >/dev/full 2>" + (dir / "err").string();
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status)) << args;
    EXPECT_EQ(WEXITSTATUS(status), 2) << args;
    const std::string err = test::read_bytes(dir / "err");
    EXPECT_NE(err.find("error: stdout: No space left on device"), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace nonplanar
