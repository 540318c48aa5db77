// slice_model's rounds (src/pipeline/slice_model.cpp): through another slicer, the stacks' run
// goes ahead of the shell planned over them (shell_before_stacks).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "nonplanar/pipeline.hpp"
#include "support/engine_print.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using test::have_prusaslicer;

namespace fs = std::filesystem;

// The rib and the small domed tower through PrusaSlicer: the tower's stack covers too little,
// so a shell over both is planned first, and refused (the tower stands above the rib: one run
// cannot print it). The stacks' run started beside that plan is the one printed: one
// PrusaSlicer started (the early one, taken by it), its stages reported after the shell's, on
// the caller's thread, and the print the one made when no shell is tried at all.
TEST(ShellBeforeStacks, ThroughAnEngineTheStacksRunThatWentAheadPrints) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("shell_before_stacks");
  const fs::path log = dir / "starts.log", exe = dir / "prusa-slicer";
  {
    std::ofstream sh(exe);
    sh << "#!/bin/sh\necho start >> '" << log.string() << "'\nexec prusa-slicer \"$@\"\n";
  }
  fs::permissions(exe, fs::perms::owner_all);
  PrintConfig c;
  const TriangleMesh mesh = test::placed(test::rib_and_small_domed_tower(), c);
  SliceJob job = make_job(c);
  job.engine.engine = Engine::prusaslicer;
  job.engine.path = exe.string();
  std::vector<std::string> stages;
  bool other_thread = false;
  const auto caller = std::this_thread::get_id();
  Context ctx;
  ctx.on_progress = [&](std::string_view stage, double) {
    if (stages.empty() || stages.back() != stage) stages.emplace_back(stage);
    other_thread |= std::this_thread::get_id() != caller;
  };
  auto r = slice_model(mesh, job, ctx);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->plan.stacks.size(), 1u);
  bool refused = false;
  for (const Notice& n : r->notices)
    refused |= n.kind == Notice::Kind::shell_refused &&
               n.text.find("through an engine") != std::string::npos;
  EXPECT_TRUE(refused);
  EXPECT_EQ(r->collisions, 0u);
  std::ifstream starts(log);
  const std::string text((std::istreambuf_iterator<char>(starts)), {});
  EXPECT_EQ(text, "start\n");
  EXPECT_FALSE(other_thread);
  const auto at = [&](const char* s) {
    return std::find(stages.begin(), stages.end(), s) - stages.begin();
  };
  ASSERT_LT(at("engine"), static_cast<long>(stages.size()));
  EXPECT_LT(at("shell"), at("engine"));
  EXPECT_LT(at("engine"), at("map back"));

  // No shell tried: the stacks at once, the same print.
  job.shells = false;
  auto plain = slice_model(mesh, job, {});
  ASSERT_TRUE(plain) << plain.error().message;
  ASSERT_EQ(plain->plan.stacks.size(), 1u);
  EXPECT_EQ(r->layers.size(), plain->layers.size());
  test::expect_same_print(r->gcode, plain->gcode);
}

// A caller that wants only the G-code (the CLI) has the paths go once it is written: the
// same program and layers, none of their paths.
TEST(KeepPaths, WithoutThemTheProgramIsTheSame) {
  PrintConfig c;
  const TriangleMesh mesh = test::placed(test::rib_and_small_domed_tower(), c);
  SliceJob job = make_job(c);
  auto kept = slice_model(mesh, job, {});
  job.keep_paths = false;
  auto released = slice_model(mesh, job, {});
  ASSERT_TRUE(kept) << kept.error().message;
  ASSERT_TRUE(released) << released.error().message;
  EXPECT_TRUE(kept->nonplanar);
  EXPECT_FALSE(kept->paths_released);
  EXPECT_TRUE(released->paths_released);
  EXPECT_EQ(released->gcode, kept->gcode);
  ASSERT_EQ(released->layers.size(), kept->layers.size());
  std::size_t points = 0;
  for (std::size_t i = 0; i < kept->layers.size(); ++i) {
    EXPECT_EQ(released->layers[i].z, kept->layers[i].z);
    EXPECT_TRUE(released->layers[i].paths.empty());
    for (const ExtrusionPath& p : kept->layers[i].paths) points += p.points.size();
  }
  EXPECT_GT(points, 1000u);
}

}  // namespace
}  // namespace nonplanar
