// `slice --timings` (#20): the stages' wall and CPU times, read from their progress reports.
#include <gtest/gtest.h>

#include <cstdlib>
#include <iterator>
#include <regex>
#include <string>

#include "support/cli.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

TEST(Timings, EveryStageOfACurvedSliceIsTimedAndTheSpansAddUp) {
  const fs::path dir = test::temp_dir("timings");
  test::write_bytes(dir / "roof.stl", test::ascii_stl(test::sine_roof(), "\n"));
  const auto r = test::run_cli("slice " + (dir / "roof.stl").string() + " -o " +
                               (dir / "roof.gcode").string() + " --timings");
  ASSERT_EQ(r.code, 0) << r.err;
  // The spans, in order, one per line: "  NAME  WALL  CPU  CORES  RSS  PEAK" (seconds, their
  // ratio, the resident size at the span's end and its high-water mark so far, MB).
  std::vector<std::string> order;
  double sum = 0, cpu = 0, peak = 0;
  const std::regex span(
      R"(\n  ([a-z ]+?) +([0-9]+\.[0-9]{3}) +([0-9]+\.[0-9]{3}) +([0-9]+\.[0-9]{2}))"
      R"( +([0-9]+\.[0-9]) +([0-9]+\.[0-9])(?=\n))");
  for (auto it = std::sregex_iterator(r.err.begin(), r.err.end(), span);
       it != std::sregex_iterator(); ++it) {
    order.push_back((*it)[1]);
    sum += std::stod((*it)[2]);
    cpu += std::stod((*it)[3]);
    const double rss = std::stod((*it)[5]), hwm = std::stod((*it)[6]);
    EXPECT_GT(rss, 2.0) << (*it)[0];  // at least the process's code and the mesh
    EXPECT_LE(rss, hwm) << (*it)[0];
    EXPECT_GE(hwm, peak) << (*it)[0];  // a high-water mark never falls
    peak = hwm;
  }
  // The gate checks the thickness, writes the program, checks its slopes, then looks for
  // collisions in it while the other core measures the file's time and filament (no "stats"
  // span of its own).
  const std::vector<std::string> want = {"load",  "analyze",    "fit",      "layers", "normalize",
                                         "slice", "toolpaths",  "map back", "gate",   "gcode",
                                         "gate",  "collisions", "write"};
  EXPECT_EQ(order, want) << r.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.err, m,
      std::regex(R"(setup ([0-9.]+), total ([0-9.]+) \(cpu ([0-9.]+)\), peak ([0-9.]+) MB\n)")))
      << r.err;
  EXPECT_NEAR(sum + std::stod(m[1]), std::stod(m[2]), 0.01);
  EXPECT_GT(sum, 0);
  // The spans' CPU time is the process's since the first span (not the setup's before it).
  EXPECT_GT(cpu, 0);
  EXPECT_LE(cpu, std::stod(m[3]) + 0.01);
  // The run's peak is the last span's mark; the mapping's resampled paths take it past 10 MB.
  EXPECT_EQ(std::stod(m[4]), peak);
  EXPECT_GT(peak, 10.0);
  // Without the flag, nothing of it.
  const auto q = test::run_cli("slice -q " + (dir / "roof.stl").string() + " -o " +
                               (dir / "roof.gcode").string());
  EXPECT_EQ(q.err.find("timings"), std::string::npos);
}

// Two reliefs through PrusaSlicer: no stack fits them, so shells are planned, and print in
// pieces between the engine's core layers (the reliefs stand above each other's shell); the
// planar attempt's plan is made once, and the engine runs once.
TEST(Timings, ThroughAnEngineTheReliefsPrintAsShellsInPieces) {
  if (std::system("command -v prusa-slicer >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("timings_engine");
  test::write_bytes(dir / "reliefs.stl", test::ascii_stl(test::two_reliefs(), "\n"));
  const auto r =
      test::run_cli("slice " + (dir / "reliefs.stl").string() + " -o " +
                    (dir / "reliefs.gcode").string() + " --engine prusaslicer --timings");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("2 curved shells"), std::string::npos) << r.err;
  for (const char* span : {"layers", "engine"}) {
    const std::regex one(std::string(R"(\n  )") + span + R"( +[0-9]+\.[0-9]{3} )");
    const auto n = std::distance(std::sregex_iterator(r.err.begin(), r.err.end(), one),
                                 std::sregex_iterator());
    EXPECT_EQ(n, 1) << span << "\n" << r.err;
  }
  EXPECT_NE(r.err.find("\n  shell "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("\n  core "), std::string::npos) << r.err;
}

}  // namespace
}  // namespace nonplanar
