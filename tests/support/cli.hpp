// Running the nonplanar CLI from a test, as a user would.
#pragma once

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <string>

#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar::test {

struct CliResult {
  int code;  ///< exit code, or 128 + signal
  std::string out, err;
};

/// Runs `nonplanar ARGS`, killed after limit_s seconds (a hang then shows as 128 + 9).
inline CliResult run_cli(const std::string& args, int limit_s = 300) {
  const auto dir = temp_dir("cli_run");
  const std::string cmd = "timeout -s KILL " + std::to_string(limit_s) + " " + NONPLANAR_CLI + " " +
                          args + " >" + (dir / "out").string() + " 2>" + (dir / "err").string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), read_bytes(dir / "out"),
          read_bytes(dir / "err")};
}

/// How many lines a text has (its line ends): a one-line error is 1.
inline std::size_t count_lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace nonplanar::test
