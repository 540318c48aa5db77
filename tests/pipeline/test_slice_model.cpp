// slice_model's rounds (src/pipeline/slice_model.cpp): through another slicer, a shell planned
// over small stacks prints where the part stands above it (shell_before_stacks).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "layers/shell_plan.hpp"
#include "nonplanar/analysis.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/pipeline.hpp"
#include "support/engine_print.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using test::have_prusaslicer;

namespace fs = std::filesystem;

// The stages a slice reports, each once in a row, and whether any came from another thread
// than the one that made the context.
struct Stages {
  std::vector<std::string> stages;
  bool other_thread = false;
  std::thread::id caller = std::this_thread::get_id();
  Context context() {
    Context ctx;
    ctx.on_progress = [this](std::string_view stage, double) {
      if (stages.empty() || stages.back() != stage) stages.emplace_back(stage);
      other_thread |= std::this_thread::get_id() != caller;
    };
    return ctx;
  }
  long at(const char* stage) const {
    return std::find(stages.begin(), stages.end(), stage) - stages.begin();
  }
};

// The rib and the small domed tower through PrusaSlicer: the tower's stack covers too little,
// so a shell over both is planned first. The tower stands above the rib, so the shell prints
// in pieces between the engine's core layers (shell_pieces_with_engine), as the built-in
// engine prints it: one PrusaSlicer started (the early one, taken by the core's run), the
// shell's stages reported on the caller's thread, its top as close to the mesh as the
// built-in engine's, and no collision.
TEST(ShellBeforeStacks, ThroughAnEngineAShellThePartStandsAbovePrintsInPieces) {
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
  Stages progress;
  const Context ctx = progress.context();
  auto r = slice_model(mesh, job, ctx);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_TRUE(r->plan.stacks.empty());
  EXPECT_EQ(r->shell_layers, 2);
  EXPECT_EQ(r->collisions, 0u);
  EXPECT_NE(r->gcode.find("; nonplanar: curved paths printed between the engine's layers"),
            std::string::npos);
  std::ifstream starts(log);
  const std::string text((std::istreambuf_iterator<char>(starts)), {});
  EXPECT_EQ(text, "start\n");
  EXPECT_FALSE(progress.other_thread);
  ASSERT_LT(progress.at("engine"), static_cast<long>(progress.stages.size()));
  EXPECT_LT(progress.at("shell"), progress.at("engine"));
  EXPECT_LT(progress.at("engine"), progress.at("core"));

  // The built-in engine's print of the same shell, and both as `check` measures them: the
  // pieces are the same, so the top is as close (0.994 both, through PrusaSlicer 2.5).
  job.engine.engine = Engine::builtin;
  auto builtin = slice_model(mesh, job, {});
  ASSERT_TRUE(builtin) << builtin.error().message;
  auto builtin_text = make_gcode(builtin->layers, c, builtin->header, {});
  ASSERT_TRUE(builtin_text) << builtin_text.error().message;
  auto figures = [&](const std::string& g) {
    auto moves = read_gcode_moves(g);
    EXPECT_TRUE(moves) << moves.error().message;
    CheckParams cp = check_params(c, 30);
    cp.min_angle_deg = 2;
    auto f = check_print(*moves, &mesh, cp, {});
    EXPECT_TRUE(f) << f.error().message;
    return *f;
  };
  const CheckFigures engine_f = figures(r->gcode), builtin_f = figures(*builtin_text);
  EXPECT_GT(builtin_f.within_share, 0.95);
  EXPECT_GT(engine_f.within_share, builtin_f.within_share - 0.02);
  EXPECT_EQ(engine_f.collisions, 0u);
}

// A tower standing on the rib's curved top: the shell prints in pieces through PrusaSlicer,
// and the run of the part on the core's boundaries, foreseen once the part is analysed
// (layers::region_shells_core), is handed to the engine started early before the shells are
// planned (they are planned at idle priority meanwhile): the engine that prints is the first
// started (a spare started beside it, for a route that would not want that run, is stopped
// unused), on the boundaries the shells' plan gives the core.
TEST(ShellBeforeStacks, ThroughAnEngineTheCoreRunsWhileTheShellsArePlanned) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("core_ahead");
  const fs::path log = dir / "runs.log", exe = dir / "prusa-slicer";
  {
    std::ofstream sh(exe);
    sh << "#!/bin/sh\necho \"start $$\" >> '" << log.string() << "'\nprusa-slicer \"$@\"\n"
       << "rc=$?\necho \"done $$\" >> '" << log.string() << "'\nexit $rc\n";
  }
  fs::permissions(exe, fs::perms::owner_all);
  PrintConfig c;
  TriangleMesh part = test::rib();
  test::append(part, test::box({45, 3, 0}, {55, 9, 20}));
  const TriangleMesh mesh = test::placed(part, c);
  const Analysis a = *analyze(mesh, {}, {});
  SliceJob job = make_job(c);
  const auto core = layers::region_shells_core(mesh, a, job.layers);
  ASSERT_TRUE(core);
  job.engine.engine = Engine::prusaslicer;
  job.engine.path = exe.string();
  // The plan, made on a thread of idle priority meanwhile, reports on the caller's thread.
  Stages progress;
  const Context ctx = progress.context();
  auto r = slice_model(mesh, job, ctx);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_FALSE(progress.other_thread);
  ASSERT_LT(progress.at("engine"), static_cast<long>(progress.stages.size()));
  EXPECT_LT(progress.at("fit"), progress.at("shell"));
  EXPECT_LT(progress.at("shell"), progress.at("engine"));
  EXPECT_EQ(r->collisions, 0u);
  EXPECT_NE(r->gcode.find("; nonplanar: curved paths printed between the engine's layers"),
            std::string::npos);
  std::ifstream runs(log);
  std::vector<std::string> lines;
  for (std::string l; std::getline(runs, l);) lines.push_back(l);
  // Two started, one finished: the first. Which shell writes its line first is up to the
  // scheduler (CI saw the spare's first), so the first started is the one forked first, the
  // lower pid (pids do not wrap within one test).
  ASSERT_EQ(lines.size(), 3u);
  std::vector<long> started;
  for (int i : {0, 1}) {
    ASSERT_EQ(lines[i].rfind("start ", 0), 0u) << lines[i];
    started.push_back(std::stol(lines[i].substr(6)));
  }
  ASSERT_EQ(lines[2].rfind("done ", 0), 0u) << lines[2];
  EXPECT_EQ(std::stol(lines[2].substr(5)), std::min(started[0], started[1]));
  // The core's boundaries are the ones foreseen.
  const std::vector<layers::ShellPlan> plans = layers::choose_shells(mesh, a, job.layers);
  ASSERT_FALSE(plans.front().region.empty());
  EXPECT_EQ(plans.front().core, *core);
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
