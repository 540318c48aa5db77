// -o as PrusaSlicer takes it: a folder, or an output-name template.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "nonplanar/io.hpp"
#include "support/cli.hpp"

namespace nonplanar {
namespace {
namespace fs = std::filesystem;

TEST(OutputPath, AFolderOrATemplateNamesTheFile) {
  const fs::path dir = test::temp_dir("output_path");
  const fs::path stl = dir / "my part.stl";
  ASSERT_TRUE(write_stl(stl, test::box({0, 0, 0}, {10, 10, 2})));
  const std::string base = "slice -q --planar '" + stl.string() + "' -o ";
  fs::create_directories(dir / "out");
  // A folder, with or without the slash: the model's name in it.
  auto r = test::run_cli(base + (dir / "out").string() + "/");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "my part.gcode"));
  fs::remove(dir / "out" / "my part.gcode");
  r = test::run_cli(base + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "my part.gcode"));
  // PrusaSlicer's template macros, profile keys included.
  r = test::run_cli(base + "'" + (dir / "[input_filename_base]_{layer_height}mm.gcode").string() +
                    "' --layer-height 0.15");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "my part_0.15mm.gcode"));
  // What the template cannot name is a one-line error, and nothing is written.
  r = test::run_cli(base + "'" + (dir / "[print_time].gcode").string() + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("'print_time' is not a variable"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  r = test::run_cli(base + (dir / "nowhere").string() + "/");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("folder does not exist"), std::string::npos) << r.err;
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 2);  // the model and my part_0.15mm.gcode
}

}  // namespace
}  // namespace nonplanar
