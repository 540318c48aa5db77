// The settings the built-in engine does not do: named when asked for, silent when off.
#include <gtest/gtest.h>

#include "nonplanar/io.hpp"
#include "nonplanar/unsupported_keys.hpp"
#include "support/cli.hpp"

namespace nonplanar {
namespace {

std::vector<std::string> named(const std::vector<std::pair<std::string, std::string>>& keys) {
  PrintConfig c;
  for (const auto& [k, v] : keys) EXPECT_TRUE(set_config_value(c, k, v)) << k;
  return unsupported_settings(c);
}

TEST(UnsupportedKeys, NamesWhatIsAskedForAndNotWhatIsOff) {
  // PrusaSlicer's own defaults (a stock profile writes every one of them): nothing to say.
  EXPECT_TRUE(named({{"support_material", "0"},
                     {"support_material_auto", "1"},
                     {"brim_width", "0"},
                     {"raft_layers", "0"},
                     {"ironing", "0"},
                     {"seam_position", "aligned"},
                     {"fuzzy_skin", "none"},
                     {"draft_shield", "disabled"},
                     {"infill_every_layers", "1"},
                     {"layer_height", "0.2"}})
                  .empty());
  const auto on = named({{"support_material", "1"},
                         {"support_material_auto", "1"},
                         {"brim_width", "5"},
                         {"seam_position", "rear"},
                         {"ironing", "1"},
                         {"layer_height", "0.2"}});
  const std::vector<std::string> want = {"brim_width = 5", "ironing = 1", "seam_position = rear",
                                         "support_material = 1", "support_material_auto = 1"};
  EXPECT_EQ(on, want);
  EXPECT_TRUE(is_unsupported_key("brim_width"));
  EXPECT_FALSE(is_unsupported_key("layer_height"));
  EXPECT_FALSE(is_unsupported_key("no_such_key"));
}

TEST(UnsupportedKeys, TheBuiltInEngineSaysWhatItLeavesOut) {
  const auto dir = test::temp_dir("unsupported");
  ASSERT_TRUE(write_stl(dir / "b.stl", test::box({0, 0, 0}, {20, 20, 5})));
  const std::string base =
      "slice " + (dir / "b.stl").string() + " --planar -o " + (dir / "b.gcode").string();
  const auto r = test::run_cli(base + " --set brim_width=5 --set support_material=1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("brim_width = 5, support_material = 1"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--engine prusaslicer"), std::string::npos) << r.err;
  const auto off = test::run_cli(base + " --set brim_width=0");
  ASSERT_EQ(off.code, 0) << off.err;
  EXPECT_EQ(off.err.find("does not print"), std::string::npos) << off.err;
  // A key nobody knows is still refused.
  EXPECT_EQ(test::run_cli(base + " --set brim_widht=5").code, 2);
}

}  // namespace
}  // namespace nonplanar
