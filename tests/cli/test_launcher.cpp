// build/nonplanar is a launcher (apps/launcher): it starts nonplanar-core beside it with
// glibc's huge-page heap, and the slicers the program runs get the user's environment.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <filesystem>
#include <string>

#include "nonplanar/io.hpp"
#include "support/cli.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

// What GLIBC_TUNABLES the engine nonplanar runs sees (this process's environment is nonplanar's).
std::string tunables_the_engine_sees() {
  const fs::path dir = test::temp_dir("launcher_env");
  EXPECT_TRUE(write_stl(dir / "b.stl", test::box({0, 0, 0}, {10, 10, 1})));
  const fs::path seen = dir / "seen", engine = dir / "engine.sh";
  test::write_bytes(
      engine, "#!/bin/sh\necho \"[${GLIBC_TUNABLES-unset}]\" > " + seen.string() + "\nexit 3\n");
  fs::permissions(engine, fs::perms::owner_all);
  const test::CliResult r =
      test::run_cli("slice -q " + (dir / "b.stl").string() + " -o " + (dir / "b.gcode").string() +
                    " --planar --engine prusaslicer --engine-path " + engine.string());
  EXPECT_EQ(r.code, 2) << r.err;  // the engine failed: the slice says so
  return test::read_bytes(seen);
}

TEST(Launcher, TheEngineGetsTheUsersEnvironment) {
  ::unsetenv("GLIBC_TUNABLES");
  EXPECT_EQ(tunables_the_engine_sees(), "[unset]\n");
  ::setenv("GLIBC_TUNABLES", "glibc.malloc.check=0", 1);
  EXPECT_EQ(tunables_the_engine_sees(), "[glibc.malloc.check=0]\n");
  ::unsetenv("GLIBC_TUNABLES");
}

TEST(Launcher, WithoutTheProgramBesideItSaysWhatIsMissing) {
  const fs::path dir = test::temp_dir("launcher_alone");
  const fs::path alone = dir / "nonplanar";
  fs::copy_file(NONPLANAR_CLI, alone, fs::copy_options::overwrite_existing);
  const std::string cmd = alone.string() + " --version 2>" + (dir / "err").string();
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1);
  const std::string err = test::read_bytes(dir / "err");
  EXPECT_NE(err.find((dir / "nonplanar-core").string()), std::string::npos) << err;
  EXPECT_EQ(test::count_lines(err), 1u) << err;
}

// lib3mf (and the zip and crypto libraries under it: 5 ms of every run's start) is loaded
// when a 3MF is read, not by a run that reads an STL.
TEST(Launcher, Lib3mfIsLoadedOnlyWhenA3mfIsRead) {
  const fs::path dir = test::temp_dir("launcher_lib3mf");
  const TriangleMesh box = test::box({0, 0, 0}, {10, 10, 1});
  ASSERT_TRUE(write_stl(dir / "b.stl", box));
  ASSERT_TRUE(write_3mf(dir / "b.3mf", box));
  auto loads = [&](const std::string& model) {
    const fs::path err = dir / "err";
    const std::string cmd = "LD_DEBUG=files " + std::string(NONPLANAR_CLI) + " analyze " +
                            (dir / model).string() + " >/dev/null 2>" + err.string();
    const int status = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::read_bytes(err);
    return test::read_bytes(err).find("lib3MF") != std::string::npos;
  };
  EXPECT_FALSE(loads("b.stl"));
  EXPECT_TRUE(loads("b.3mf"));
}

}  // namespace
}  // namespace nonplanar
