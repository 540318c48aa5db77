// Curved tops from inside PrusaSlicer (#17): `prepare` writes the normalised part as a 3MF,
// PrusaSlicer slices it with its post-processing script set to `post-process`, which maps
// the G-code back. Run with Debian's prusa-slicer as a user would; skipped without it.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/sanitizers.hpp"
#include "nonplanar/io.hpp"
#include "support/cli.hpp"
#include "support/engine_print.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using test::have_prusaslicer;

namespace fs = std::filesystem;

// prusa-slicer ARGS; its exit code, and its log in *log.
int prusa(const std::string& args, std::string* log = nullptr) {
  const fs::path dir = test::temp_dir("prusa_run");
  const int st = std::system(
      ("timeout -s KILL 300 prusa-slicer " + args + " >" + (dir / "log").string() + " 2>&1")
          .c_str());
  if (log) *log = test::read_bytes(dir / "log");
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

std::string post_process_line(const fs::path& plan) {
  return std::string("--post-process '") + NONPLANAR_CLI + " post-process --plan " + plan.string() +
         "'";
}

nlohmann::json figures(const fs::path& gcode, const fs::path& mesh) {
  const auto c = test::run_cli("check -q --json " + gcode.string() + " --mesh " + mesh.string());
  EXPECT_EQ(c.code, 0) << c.err;
  return c.code == 0 ? nlohmann::json::parse(c.out) : nlohmann::json{};
}

// A part `prepare` wrote for `mesh`: dir/NAME.stl and dir/NAME.3mf.
fs::path prepared(const fs::path& dir, const std::string& name, const TriangleMesh& mesh) {
  EXPECT_TRUE(write_stl(dir / (name + ".stl"), mesh));
  const auto r = test::run_cli("prepare " + (dir / (name + ".stl")).string() + " -o " +
                               (dir / (name + ".3mf")).string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("post-process --plan " + (dir / (name + ".3mf")).string()),
            std::string::npos)
      << r.err;
  return dir / (name + ".3mf");
}

TEST(PostProcessRoute, CurvedTopsLikeTheEngineRoute) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_route");
  for (const auto& [name, mesh] :
       {std::pair{"dome", test::dome_cut_by_box()}, {"saddle", test::saddle()}}) {
    SCOPED_TRACE(name);
    const fs::path plan = prepared(dir, name, mesh), out = dir / (std::string(name) + ".gcode");
    std::string log;
    ASSERT_EQ(prusa("--export-gcode --first-layer-height 0.2 " + post_process_line(plan) + " -o " +
                        out.string() + " " + plan.string(),
                    &log),
              0)
        << log;
    const std::string text = test::read_bytes(out);
    // PrusaSlicer centres the part on its own 200 mm bed; the plan was made on our 220 mm one.
    EXPECT_NE(text.find("the part moved by -10.000, -10.000 mm"), std::string::npos);
    const auto ours = figures(out, dir / (std::string(name) + ".stl"));
    EXPECT_LE(ours["top_surface_deviation"]["p95"].get<double>(), 0.02);
    EXPECT_EQ(ours["collisions"], 0);
    EXPECT_GT(ours["steepest_extrusion"].get<double>(), 10);
    const fs::path engine = dir / (std::string(name) + ".engine.gcode");
    const auto e =
        test::run_cli("slice -q " + (dir / (std::string(name) + ".stl")).string() +
                      " --engine prusaslicer --first-layer-height 0.2 -o " + engine.string());
    ASSERT_EQ(e.code, 0) << e.err;
    const auto theirs = figures(engine, dir / (std::string(name) + ".stl"));
    EXPECT_NEAR(ours["top_surface_deviation"]["p95"].get<double>(),
                theirs["top_surface_deviation"]["p95"].get<double>(), 0.005);
    EXPECT_NEAR(ours["volume_ratio"].get<double>(), theirs["volume_ratio"].get<double>(), 0.02);
  }
}

// As the GUI runs it: the script gets NAME.gcode.pp in a temporary folder and the final name
// in SLIC3R_PP_OUTPUT_NAME; the plan is the 3MF of that name, or the one holding the object
// the labels name.
TEST(PostProcessRoute, FindsThePlanAsTheSlicerRunsIt) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_find");
  const fs::path plan = prepared(dir, "dome", test::dome_cut_by_box());
  const fs::path raw = dir / "raw.gcode";
  ASSERT_EQ(
      prusa("--export-gcode --first-layer-height 0.2 -o " + raw.string() + " " + plan.string()), 0);
  fs::create_directories(dir / "tmp");
  const fs::path pp = dir / "tmp" / "7f3a.gcode.pp";
  fs::copy_file(raw, pp);
  const auto lost = test::run_cli("post-process " + pp.string());
  EXPECT_EQ(lost.code, 2);  // without the final name there is no plan beside the temporary file
  EXPECT_NE(lost.err.find("no plan found (looked for " + (dir / "tmp" / "7f3a.3mf").string()),
            std::string::npos)
      << lost.err;
  setenv("SLIC3R_PP_OUTPUT_NAME", (dir / "dome.gcode").c_str(), 1);
  const auto r = test::run_cli("post-process " + pp.string());
  unsetenv("SLIC3R_PP_OUTPUT_NAME");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("mapped dome.gcode onto the curved layers of dome"), std::string::npos)
      << r.err;
  EXPECT_EQ(test::read_bytes(pp).rfind("; post-processed by nonplanar", 0), 0u);
  // Object labels name the part; the G-code is named otherwise.
  const fs::path labelled = dir / "whatever.gcode";
  std::string log;
  ASSERT_EQ(prusa("--export-gcode --first-layer-height 0.2 --gcode-label-objects "
                  "--use-relative-e-distances --post-process '" +
                      std::string(NONPLANAR_CLI) + " post-process' -o " + labelled.string() + " " +
                      plan.string(),
                  &log),
            0)
      << log;
  const auto rel = figures(labelled, dir / "dome.stl");  // relative E, too
  EXPECT_LE(rel["top_surface_deviation"]["p95"].get<double>(), 0.02);
  EXPECT_NEAR(rel["volume_ratio"].get<double>(),
              figures(pp, dir / "dome.stl")["volume_ratio"].get<double>(), 0.01);
  EXPECT_NE(test::read_bytes(labelled).find("\nM83"), std::string::npos);
}

TEST(PostProcessRoute, RefusalsLeaveTheSlicersFileUntouched) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_refuse");
  const fs::path plan = prepared(dir, "dome", test::dome_cut_by_box());
  struct Case {
    std::string prusa_args, says;
  };
  for (const Case& c : {Case{"", "the first layer is 0.350 mm, the plan's 0.200 mm"},
                        Case{"--first-layer-height 0.2 --rotate 30", "scaled or rotated"},
                        Case{"--first-layer-height 0.2 --scale 110%", "scaled or rotated"}}) {
    SCOPED_TRACE(c.prusa_args);
    const fs::path out = dir / "out.gcode";
    ASSERT_EQ(prusa("--export-gcode " + c.prusa_args + " -o " + out.string() + " " + plan.string()),
              0);
    const std::string before = test::read_bytes(out);
    const auto r = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.rfind("error: " + out.string() + ": ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(test::read_bytes(out), before);
  }
}

// Supports and brim are the slicer's: they are mapped with the field like everything else.
TEST(PostProcessRoute, SupportsAndBrimFollow) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_support");
  // The dome 8 mm up on a 6 mm post: its underside needs support.
  TriangleMesh part = test::dome_cut_by_box();
  for (Vec3& v : part.vertices) v.z() += 8;
  test::append(part, test::box({-3, -3, 0}, {3, 3, 8.5}));
  const fs::path plan = prepared(dir, "perched", part), out = dir / "perched.gcode";
  std::string log;
  ASSERT_EQ(prusa("--export-gcode --first-layer-height 0.2 --support-material --brim-width 3 " +
                      post_process_line(plan) + " -o " + out.string() + " " + plan.string(),
                  &log),
            0)
      << log;
  const std::string text = test::read_bytes(out);
  EXPECT_NE(text.find(";TYPE:Support material\n"), std::string::npos);
  const auto f = figures(out, dir / "perched.stl");
  EXPECT_LE(f["top_surface_deviation"]["p95"].get<double>(), 0.02);
  EXPECT_EQ(f["collisions"], 0);
  // The engine route reads the same beads: the part's layer after a support-only one is the
  // part's thickness, not the distance from the supports' (which once failed the gate with
  // "a layer leaves the thickness limits").
  const fs::path engine = dir / "engine.gcode";
  const auto e =
      test::run_cli("slice -q " + (dir / "perched.stl").string() +
                    " --engine prusaslicer --set support_material=1 -o " + engine.string());
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_NE(test::read_bytes(engine).find(";TYPE:Support material\n"), std::string::npos);
  EXPECT_EQ(figures(engine, dir / "perched.stl")["collisions"], 0);
}

// The extrusions between a line starting `start` and one starting `stop`, without their E (the
// writer rounds E the same way, but the point is where the nozzle goes).
std::vector<std::string> lines_between(const std::string& text, const std::string& start,
                                       const std::string& stop) {
  std::vector<std::string> out;
  bool in = false;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) {
    if (l.rfind(start, 0) == 0) in = true;
    if (l.rfind(stop, 0) == 0) in = false;
    if (!in || l.rfind("G1 X", 0) != 0 || l.find(" E") == std::string::npos) continue;
    std::stringstream w(l.substr(0, l.find(" E")));
    double x, y;
    char c;
    std::string g;
    w >> g >> c >> x >> c >> y;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f %.3f", x, y);
    out.push_back(buf);
  }
  return out;
}

// An object's extrusions inside its PrusaSlicer labels.
std::vector<std::string> lines_of_object(const std::string& text, const std::string& name) {
  return lines_between(text, "; printing object " + name, "; stop printing object " + name);
}

// A plate of the prepared part and another object: with object labels the other one is left
// as the slicer wrote it; without, post-process cannot tell them apart and says so.
TEST(PostProcessRoute, OtherObjectsOnThePlateAreLeftAlone) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_plate");
  const fs::path plan = prepared(dir, "dome", test::dome_cut_by_box());
  ASSERT_TRUE(write_stl(dir / "cube.stl", test::box({0, 0, 0}, {15, 15, 6})));
  const fs::path out = dir / "plate.gcode";
  const std::string inputs = " --merge " + plan.string() + " " + (dir / "cube.stl").string();
  ASSERT_EQ(prusa("--export-gcode --first-layer-height 0.2 --gcode-label-objects -o " +
                  out.string() + inputs),
            0);
  const std::string before = test::read_bytes(out);
  const auto r = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("mapped plate.gcode onto the curved layers of dome"), std::string::npos);
  EXPECT_NE(r.err.find("steepest extrusion 2"), std::string::npos) << r.err;  // 20-odd degrees
  const std::string after = test::read_bytes(out);
  const auto cube = lines_of_object(before, "cube");
  EXPECT_GT(cube.size(), 100u);
  EXPECT_EQ(lines_of_object(after, "cube"), cube);
  EXPECT_NE(lines_of_object(after, "dome"), lines_of_object(before, "dome"));
  EXPECT_EQ(figures(out, dir / "dome.stl")["collisions"], 0);
  // Without labels.
  ASSERT_EQ(prusa("--export-gcode --first-layer-height 0.2 -o " + out.string() + inputs), 0);
  const auto u = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
  EXPECT_EQ(u.code, 2);
  EXPECT_NE(u.err.find("switch on Label objects"), std::string::npos) << u.err;
}

// PrusaSlicer's labels rewritten as a Bambu Lab printer's (OrcaSlicer, Bambu Studio): "; start
// printing object, unique label id: N" and an M624 mask / "; stop printing object, unique label
// id: N" and M625, no names.
std::string bambu_labels(const std::string& text) {
  std::string out;
  std::stringstream ss(text);
  std::map<std::string, int> ids;
  for (std::string l; std::getline(ss, l);) {
    if (l.rfind("; printing object ", 0) == 0) {
      const int id = ids.emplace(l.substr(18), static_cast<int>(ids.size()) + 1).first->second;
      out += "; start printing object, unique label id: " + std::to_string(id) +
             "\nM624 AQAAAAAAAAA=\n";
    } else if (l.rfind("; stop printing object ", 0) == 0) {
      const int id = ids.at(l.substr(23));
      out += "; stop printing object, unique label id: " + std::to_string(id) + "\nM625\n";
    } else {
      out += l + "\n";
    }
  }
  return out;
}

// Labels without names: the part is the one object of the plan's size; two of that size are
// refused, naming why.
TEST(PostProcessRoute, BambuLabelsFindThePartBySize) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_bambu");
  const fs::path plan = prepared(dir, "dome", test::dome_cut_by_box());
  for (const double side : {15.0, 24.0}) {
    ASSERT_TRUE(write_stl(dir / "cube.stl", test::box({0, 0, 0}, {side, side, 6})));
    const fs::path out = dir / "plate.gcode";
    ASSERT_EQ(prusa("--export-gcode --first-layer-height 0.2 --gcode-label-objects -o " +
                    out.string() + " --merge " + plan.string() + " " + (dir / "cube.stl").string()),
              0);
    const std::string before = test::read_bytes(out);
    test::write_bytes(out, bambu_labels(before));
    const auto r = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
    if (side == 24.0) {  // the dome's box is 24 x 24 mm too
      EXPECT_EQ(r.code, 2);
      EXPECT_NE(r.err.find("labelled by number only (Bambu Lab's labels)"), std::string::npos)
          << r.err;
      continue;
    }
    ASSERT_EQ(r.code, 0) << r.err;
    // The cube's lines as written, the dome's mapped.
    const std::string after = test::read_bytes(out), labelled = bambu_labels(before);
    const auto cube = lines_of_object(before, "cube");
    ASSERT_GT(cube.size(), 100u);
    int kept = 0;
    for (const char* id : {"1", "2"}) {
      const std::string start = std::string("; start printing object, unique label id: ") + id,
                        stop = std::string("; stop printing object, unique label id: ") + id;
      const auto now = lines_between(after, start, stop);
      if (now != lines_between(labelled, start, stop)) continue;
      ++kept;
      EXPECT_EQ(now, cube);
    }
    EXPECT_EQ(kept, 1);
    const auto f = figures(out, dir / "dome.stl");
    EXPECT_EQ(f["collisions"], 0);
    EXPECT_LE(f["top_surface_deviation"]["p95"].get<double>(), 0.02);
  }
}

// The plan checked with PrusaSlicer's own paths for the user's presets (here the stock MK3S's),
// then PrusaSlicer slices and post-process maps it.
TEST(PostProcessRoute, APlanCheckedWithPrusaSlicersPaths) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_checked");
  ASSERT_TRUE(write_stl(dir / "saddle.stl", test::saddle()));
  const auto r = test::run_cli("prepare " + (dir / "saddle.stl").string() + " -o " +
                               (dir / "saddle.3mf").string() +
                               " --check-with prusaslicer --set first_layer_height=0.2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("1 curved stack"), std::string::npos) << r.err;
  const fs::path out = dir / "saddle.gcode";
  ASSERT_EQ(
      prusa("--export-gcode --first-layer-height 0.2 " + post_process_line(dir / "saddle.3mf") +
            " -o " + out.string() + " " + (dir / "saddle.3mf").string()),
      0);
  const auto f = figures(out, dir / "saddle.stl");
  EXPECT_LE(f["top_surface_deviation"]["p95"].get<double>(), 0.02);
  EXPECT_EQ(f["collisions"], 0);
  const auto bad = test::run_cli("prepare " + (dir / "saddle.stl").string() + " -o " +
                                 (dir / "x.3mf").string() + " --check-with cura");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--check-with: 'cura' is not builtin or prusaslicer"), std::string::npos);
}

// The first layer height prepare asks for ("first layer height 0.18 mm").
std::string first_layer(const std::string& err) {
  const auto at = err.find("first layer height ");
  if (at == std::string::npos) return "?";
  return err.substr(at + 19, err.find(' ', at + 19) - at - 19);
}

// A part whose top prints as a curved shell over a planar core: the 3MF holds the part with the
// shell's slab above it and the layer-height profile of both; one PrusaSlicer run slices them
// and post-process lays the slab's layers on the part (#17). Scored as the engine route's two
// runs; the wing (shared model) is not symmetric, so its offset is found by its outline's
// centroid, not its box (which put it 0.08 mm off, and its p95 at 0.036 against 0.012 mm).
TEST(PostProcessRoute, AShellOverAPlanarCoreLikeTheEngineRoute) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_shell");
  std::vector<std::pair<std::string, fs::path>> parts{{"rib", dir / "rib.stl"}};
  ASSERT_TRUE(write_stl(parts[0].second, test::rib()));
#ifndef NONPLANAR_ASAN  // the rib's code path; the wing adds 20 s under AddressSanitizer
  if (const fs::path m = test::shared_models(); !m.empty())
    parts.emplace_back("wing", m / "np_curvislicer_wing.stl");
#endif
  for (const auto& [name, stl] : parts) {
    SCOPED_TRACE(name);
    const fs::path plan = dir / (name + ".3mf"), out = dir / (name + ".gcode");
    const auto p = test::run_cli("prepare " + stl.string() + " -o " + plan.string());
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_NE(p.err.find("a curved shell of 2 layers over a planar core"), std::string::npos)
        << p.err;
    auto profile = read_3mf_part(plan, "Metadata/Slic3r_PE_layer_heights_profile.txt");
    ASSERT_TRUE(profile) << profile.error().message;
    EXPECT_EQ(profile->rfind("object_id=1|", 0), 0u);
    std::string log;
    ASSERT_EQ(prusa("--export-gcode --first-layer-height " + first_layer(p.err) + " " +
                        post_process_line(plan) + " -o " + out.string() + " " + plan.string(),
                    &log),
              0)
        << log;
    const std::string text = test::read_bytes(out);
    EXPECT_NE(text.find("the part moved by -10.000, -10.000 mm"), std::string::npos)
        << text.substr(0, 300);
    const auto ours = figures(out, stl);
    EXPECT_LE(ours["top_surface_deviation"]["p95"].get<double>(), 0.02);
    EXPECT_EQ(ours["collisions"], 0);
    EXPECT_GT(ours["steepest_extrusion"].get<double>(), 10);  // curved
    EXPECT_GE(ours["thickness_min"].get<double>(), 0.1 - 1e-3);
    const fs::path engine = dir / (name + ".engine.gcode");
    const auto e =
        test::run_cli("slice -q " + stl.string() + " --engine prusaslicer -o " + engine.string());
    ASSERT_EQ(e.code, 0) << e.err;
    const auto theirs = figures(engine, stl);
    EXPECT_NEAR(ours["top_surface_deviation"]["p95"].get<double>(),
                theirs["top_surface_deviation"]["p95"].get<double>(), 0.005);
    EXPECT_NEAR(ours["volume_ratio"].get<double>(), theirs["volume_ratio"].get<double>(), 0.02);
  }
}

// The shell's layers are the 3MF's profile: a slicer that dropped it (the part sliced in even
// layers) gets one line saying so, and its file stays as it wrote it.
TEST(PostProcessRoute, AShellRefusesLayersOffItsProfile) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_shell_profile");
  ASSERT_TRUE(write_stl(dir / "rib.stl", test::rib()));
  const fs::path plan = dir / "rib.3mf";
  const auto p = test::run_cli("prepare " + (dir / "rib.stl").string() + " -o " + plan.string());
  ASSERT_EQ(p.code, 0) << p.err;
  // The same part without its profile: the 3MF's mesh as an STL.
  auto part = load_mesh(plan, {}, {});
  ASSERT_TRUE(part) << part.error().message;
  ASSERT_TRUE(write_stl(dir / "flat.stl", part->mesh));
  const fs::path out = dir / "flat.gcode";
  ASSERT_EQ(prusa("--export-gcode --first-layer-height " + first_layer(p.err) + " -o " +
                  out.string() + " " + (dir / "flat.stl").string()),
            0);
  const std::string before = test::read_bytes(out);
  const auto r = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("where the plan's shell begins: keep the object's layer-height profile"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(test::read_bytes(out), before);
}

// A shell on a plate with other objects: they print with the core as the slicer wrote them,
// and the shell after them all. A shorter object beside it is no matter; a taller one within
// the head's reach is (refused, naming it); the same one farther off is not. check places the
// mesh where the header says the slicer put it.
TEST(PostProcessRoute, AShellPrintsAfterTheOtherObjectsOnThePlate) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_shell_plate");
  ASSERT_TRUE(write_stl(dir / "rib.stl", test::rib()));
  ASSERT_TRUE(write_stl(dir / "cube.stl", test::box({0, 0, 0}, {15, 15, 6})));
  ASSERT_TRUE(write_stl(dir / "tower.stl", test::box({0, 0, 0}, {10, 10, 25})));
  ASSERT_TRUE(write_stl(dir / "far.stl", test::box({170, 160, 0}, {180, 170, 25})));
  const fs::path plan = dir / "rib.3mf", out = dir / "plate.gcode";
  const auto p = test::run_cli("prepare " + (dir / "rib.stl").string() + " -o " + plan.string());
  ASSERT_EQ(p.code, 0) << p.err;
  auto slice = [&](const std::string& other, const std::string& how) {
    return prusa("--export-gcode --gcode-label-objects --merge --first-layer-height " +
                 first_layer(p.err) + " " + how + " -o " + out.string() + " " + plan.string() +
                 " " + (dir / other).string());
  };
  const auto run = [&] {
    return test::run_cli("post-process --plan " + plan.string() + " " + out.string());
  };
  ASSERT_EQ(slice("cube.stl", ""), 0);
  const std::string before = test::read_bytes(out);
  const auto r = run();
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string after = test::read_bytes(out);
  const auto cube = lines_of_object(before, "cube");
  EXPECT_GT(cube.size(), 100u);
  EXPECT_EQ(lines_of_object(after, "cube"), cube);
  EXPECT_EQ(after.find("the part moved by -10.000, -10.000 mm"), std::string::npos);  // arranged
  const auto ours = figures(out, dir / "rib.stl");
  EXPECT_LE(ours["top_surface_deviation"]["p95"].get<double>(), 0.005);
  EXPECT_EQ(ours["collisions"], 0);
  EXPECT_GT(ours["steepest_extrusion"].get<double>(), 10);  // curved
  // The tower, arranged beside the rib, stands 7 mm from it and 13 mm above its top.
  ASSERT_EQ(slice("tower.stl", ""), 0);
  const std::string tower = test::read_bytes(out);
  const auto t = run();
  EXPECT_EQ(t.code, 2);
  EXPECT_NE(t.err.find("may be in its way: move them farther apart or print them separately"),
            std::string::npos)
      << t.err;
  EXPECT_EQ(test::read_bytes(out), tower);
  ASSERT_EQ(slice("far.stl", "--dont-arrange"), 0);
  const auto f = run();
  ASSERT_EQ(f.code, 0) << f.err;
  const auto far = figures(out, dir / "rib.stl");
  EXPECT_NEAR(far["top_surface_deviation"]["p95"].get<double>(),
              ours["top_surface_deviation"]["p95"].get<double>(), 1e-3);
  EXPECT_EQ(far["collisions"], 0);
  // The shell is entered from over the tower's top, not by going down through it.
  const std::string text = test::read_bytes(out);
  const auto entry = text.find("; nonplanar: the shell's curved layers");
  ASSERT_NE(entry, std::string::npos);
  double top = 0;
  ASSERT_EQ(std::sscanf(text.c_str() + text.find('\n', entry) + 1, "G1 Z%lf", &top), 1);
  EXPECT_GT(top, 25.0);
}

// The slab stands above the part in the 3MF, and PrusaSlicer would support its underside
// (columns from the part's top and from the bed beside it): prepare puts a support blocker
// there, so supports on prints none for it. Without the blocker, post-process leaves out those
// in the shell's layers (as the engine route would) and the core's cut takes
// those on the part where the shell goes; the shell prints as without them.
TEST(PostProcessRoute, AShellPrintsNoSupportsUnderItsSlab) {
  if (!have_prusaslicer()) GTEST_SKIP() << "prusa-slicer not installed";
  const fs::path dir = test::temp_dir("pp_shell_supports");
  ASSERT_TRUE(write_stl(dir / "rib.stl", test::rib()));
  const fs::path plan = dir / "rib.3mf", out = dir / "rib.gcode";
  // Four curved layers: a slab thick enough that PrusaSlicer supports it without the blocker.
  const auto p = test::run_cli("prepare " + (dir / "rib.stl").string() + " -o " + plan.string() +
                               " --set shell_layers=4");
  ASSERT_EQ(p.code, 0) << p.err;
  const std::string slice = "--export-gcode --first-layer-height " + first_layer(p.err) +
                            " --support-material -o " + out.string() + " ";
  ASSERT_EQ(prusa(slice + plan.string()), 0);
  EXPECT_EQ(test::read_bytes(out).find(";TYPE:Support"), std::string::npos);
  const auto r = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("notice: left out "), std::string::npos) << r.err;
  const auto blocked = figures(out, dir / "rib.stl");
  EXPECT_LE(blocked["top_surface_deviation"]["p95"].get<double>(), 0.005);
  EXPECT_EQ(blocked["collisions"], 0);

  // The same 3MF without the blocker.
  auto part = load_mesh(plan, test::unplaced(), {});
  ASSERT_TRUE(part) << part.error().message;
  std::vector<PackageFile> files;
  for (const char* name :
       {"Metadata/nonplanar_plan.json", "Metadata/Slic3r_PE_layer_heights_profile.txt"}) {
    auto text = read_3mf_part(plan, name);
    ASSERT_TRUE(text) << name;
    files.push_back({std::string("/") + name, *text});
  }
  const fs::path bare = dir / "rib_bare.3mf";
  ASSERT_TRUE(write_3mf(bare, part->mesh, files, {"rib", {{"layer_height", "0.2"}}, {}}));
  ASSERT_EQ(prusa(slice + bare.string()), 0);
  const std::string before = test::read_bytes(out);
  const auto shell_layers = before.find("\n;Z:12.1\n");
  ASSERT_NE(shell_layers, std::string::npos);
  ASSERT_NE(before.find(";TYPE:Support material", shell_layers), std::string::npos);
  const auto b = test::run_cli("post-process --plan " + plan.string() + " " + out.string());
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(b.err.find("notice: left out "), std::string::npos) << b.err;
  const std::string after = test::read_bytes(out);
  const auto shell = after.find("; nonplanar: the shell's curved layers");
  ASSERT_NE(shell, std::string::npos);
  EXPECT_EQ(after.find(";TYPE:Support material\n", shell), std::string::npos);
  // The core ended on a support column beside the part: the shell is entered from above,
  // not by a layer change mapped there (which went to z = -0.3).
  EXPECT_EQ(after.find(" Z-"), std::string::npos);
  const auto left_out = figures(out, dir / "rib.stl");
  EXPECT_NEAR(left_out["top_surface_deviation"]["p95"].get<double>(),
              blocked["top_surface_deviation"]["p95"].get<double>(), 1e-3);
  EXPECT_EQ(left_out["collisions"], 0);
}

TEST(PrepareCli, APartWithNothingToPlanIsRefused) {
  const fs::path dir = test::temp_dir("prepare_refuse");
  // Its shell would print beside the tower standing above it: one slicer run cannot.
  ASSERT_TRUE(write_stl(dir / "rib.stl", test::rib_beside_tower()));
  const auto r =
      test::run_cli("prepare " + (dir / "rib.stl").string() + " -o " + (dir / "rib.3mf").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nothing prints curved"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("in one slicer run a shell prints only where the part stands nowhere above"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "rib.3mf"));
  const auto bad = test::run_cli("prepare " + (dir / "rib.stl").string() + " -o " +
                                 (dir / "rib.gcode").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("prepare writes a .3mf"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace nonplanar
