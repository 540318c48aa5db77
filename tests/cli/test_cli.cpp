// The CLI as a user runs it: exit codes, one-line errors, JSON keys, exported files.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "support/cli.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using test::CliResult;
CliResult run(const std::string& args) {
  return test::run_cli(args);
}

TEST(Cli, AnalyzeJsonReportsPatches) {
  const auto dir = test::temp_dir("cli_json");
  const double t = std::tan(15.0 * M_PI / 180.0);
  ASSERT_TRUE(write_stl(
      dir / "roof.stl",
      test::height_field_solid([&](double x, double) { return 5 + t * (10 - std::abs(x - 10)); }, 0,
                               20, 0, 30, 8, 6)));
  const CliResult r = run("analyze --json " + (dir / "roof.stl").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["painted_faces"], 96);
  EXPECT_EQ(j["nonplanar_patches"], 2);
  ASSERT_EQ(j["patches"].size(), 2u);
  EXPECT_TRUE(j["patches"][0]["needs_nonplanar"].get<bool>());
  EXPECT_NEAR(j["patches"][0]["max_slope"].get<double>(), 15.0, 1e-4);  // float STL
  EXPECT_EQ(j["mesh"]["bbox_min"][2], 0.0);
}

TEST(Cli, ExportPatchesWritesAColouredPly) {
  const auto dir = test::temp_dir("cli_ply");
  ASSERT_TRUE(write_stl(dir / "s.stl", test::icosphere({0, 0, 0}, 15, 3)));
  const CliResult r = run("analyze -q " + (dir / "s.stl").string() + " --export-patches " +
                          (dir / "p.ply").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string ply = test::read_bytes(dir / "p.ply");
  EXPECT_EQ(ply.rfind("ply\nformat ascii 1.0\n", 0), 0u);
  EXPECT_NE(ply.find("element face 1280\n"), std::string::npos);
}

TEST(Cli, BadInputIsOneLineAndExitTwo) {
  const auto dir = test::temp_dir("cli_bad");
  test::write_bytes(dir / "empty.stl", "");
  test::write_bytes(dir / "junk.obj", "v 1 2 3\nf 1 2 3\n");
  for (const std::string f : {"empty.stl", "junk.obj", "missing.off"}) {
    const CliResult r = run("analyze " + (dir / f).string());
    EXPECT_EQ(r.code, 2) << f;
    EXPECT_EQ(r.err.rfind("error: " + (dir / f).string() + ": ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  const CliResult bad_angle = run("analyze --max-angle 95 " + (dir / "empty.stl").string());
  EXPECT_EQ(bad_angle.code, 2);
}

TEST(Cli, FitReportsErrorsAndExportsSurfaces) {
  const auto dir = test::temp_dir("cli_fit");
  ASSERT_TRUE(write_stl(
      dir / "w.stl", test::height_field_solid(
                         [](double x, double y) { return 6 + std::sin(x / 4) * std::cos(y / 5); },
                         0, 30, 0, 20, 90, 60)));
  const CliResult r = run("fit --json " + (dir / "w.stl").string() + " --export-surfaces " +
                          (dir / "s.json").string() + " --export-mesh " + (dir / "s.obj").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["surfaces"].size(), 1u);
  const auto& s = j["surfaces"][0];
  EXPECT_LE(s["rms_error"].get<double>(), 0.005);
  EXPECT_LE(s["max_error"].get<double>(), 0.02);
  EXPECT_GE(s["control_grid"][0].get<int>(), 4);
  // The polynomial fit met the tolerance, so the default stops there ...
  EXPECT_EQ(s["nonlinear"]["solver"], "none");
  // ... and --always-refine runs the rational and Levenberg–Marquardt steps, lowering the error.
  const CliResult full = run("fit --json --always-refine " + (dir / "w.stl").string());
  ASSERT_EQ(full.code, 0) << full.err;
  const auto fs = nlohmann::json::parse(full.out)["surfaces"][0];
  EXPECT_EQ(fs["nonlinear"]["solver"], "levenberg-marquardt");
  EXPECT_GT(fs["nonlinear"]["iterations"].get<int>(), 0);
  EXPECT_LE(fs["rms_error"].get<double>(), s["rms_error"].get<double>());
  const auto doc = nlohmann::json::parse(test::read_bytes(dir / "s.json"));
  EXPECT_EQ(doc["format"], "nonplanar-surfaces");
  EXPECT_EQ(doc["surfaces"][0]["control_points"].size(), doc["surfaces"][0]["weights"].size());
  EXPECT_FALSE(test::read_bytes(dir / "s.obj").empty());
  EXPECT_EQ(run("fit --solver bogus " + (dir / "w.stl").string()).code, 2);
}

TEST(Cli, LayersReportsStacksAndWritesTheirFiles) {
  const auto dir = test::temp_dir("cli_layers");
  ASSERT_TRUE(write_stl(dir / "roof.stl", test::sine_roof()));
  const CliResult r =
      run("layers --json " + (dir / "roof.stl").string() + " --export-layers " +
          (dir / "l.json").string() + " --export-normalized " + (dir / "n.stl").string() +
          " --section " + (dir / "s.svg").string() + " --at y=110");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["stacks"].size(), 1u);
  const auto& st = j["stacks"][0];
  EXPECT_GE(st["thickness_min"].get<double>(), 0.1 - 1e-9);
  EXPECT_LE(st["thickness_max"].get<double>(), 0.3 + 1e-9);
  EXPECT_LE(st["max_slope"].get<double>(), 30.0);
  EXPECT_GT(st["layers"].get<int>(), 3);
  const auto layers = nlohmann::json::parse(test::read_bytes(dir / "l.json"));
  EXPECT_EQ(layers["surfaces"].size(), st["layers"].get<std::size_t>() + 1);
  EXPECT_EQ(layers["surfaces"][0]["layer"], 0);
  EXPECT_TRUE(layers["surfaces"][0].contains("footprint"));
  auto n = load_mesh(dir / "n.stl", test::unplaced(), {});
  ASSERT_TRUE(n) << n.error().message;
  EXPECT_TRUE(n->defects.closed());
  const std::string svg = test::read_bytes(dir / "s.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("#e8700a"), std::string::npos);  // curved layers are drawn
  EXPECT_EQ(run("layers --section x.svg --at z=3 " + (dir / "roof.stl").string()).code, 2);
  EXPECT_EQ(run("layers --max-layer-height 0.6 " + (dir / "roof.stl").string()).code, 2);
}

// A part no stack can follow: `layers` says what `slice` prints instead, and `slice` does it.
TEST(Cli, LayersAndSliceReportTheShell) {
  const auto dir = test::temp_dir("cli_shell");
  ASSERT_TRUE(write_stl(dir / "rib.stl", test::rib()));
  const CliResult r = run("layers -q " + (dir / "rib.stl").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("0 curved stacks"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("shell: patch 0 as 2 curved layers of 0.20 mm over"), std::string::npos)
      << r.out;
  const CliResult s =
      run("slice " + (dir / "rib.stl").string() + " -o " + (dir / "r.gcode").string());
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.err.find("a curved shell of 2 layers"), std::string::npos) << s.err;
  EXPECT_NE(test::read_bytes(dir / "r.gcode").find("; patch 0: a shell of 2 curved layers"),
            std::string::npos);
}

// A stack and a shell in one part: `layers` names the shell beside the stack, `slice` prints both.
TEST(Cli, LayersAndSliceReportAShellBesideAStack) {
  const auto dir = test::temp_dir("cli_beside");
  ASSERT_TRUE(write_stl(dir / "p.stl", test::rib_and_domed_tower()));
  const CliResult r = run("layers -q " + (dir / "p.stl").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("1 curved stack,"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("shell beside the stacks: patch 1 as 2 curved layers"), std::string::npos)
      << r.out;
  const CliResult s =
      run("slice " + (dir / "p.stl").string() + " -o " + (dir / "p.gcode").string());
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.err.find("patch 1: curved shell over a planar core (1 curved stack beside it)"),
            std::string::npos)
      << s.err;
  const std::string g = test::read_bytes(dir / "p.gcode");
  EXPECT_NE(g.find("; patch 1: a shell of 2 curved layers"), std::string::npos);
  EXPECT_NE(g.find("; patch 0: "), std::string::npos);
}

TEST(Cli, SlicePlanarWritesGcodeAndRefusesBadSettings) {
  const auto dir = test::temp_dir("cli_slice");
  ASSERT_TRUE(write_stl(dir / "c.stl", test::box({0, 0, 0}, {20, 20, 10})));
  const std::string model = (dir / "c.stl").string(), out = (dir / "c.gcode").string();
  const CliResult r = run("slice -q " + model + " -o " + out +
                          " --planar --layer-height 0.25 --temperature 222 --gcode-flavor klipper");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string g = test::read_bytes(out);
  EXPECT_NE(g.find(";FLAVOR:klipper"), std::string::npos);
  EXPECT_NE(g.find(";HEIGHT:0.250"), std::string::npos);
  EXPECT_NE(g.find(";TYPE:External perimeter"), std::string::npos);
  EXPECT_NE(g.find(";TYPE:Top solid infill"), std::string::npos);
  EXPECT_EQ(std::count(g.begin(), g.end(), '\n') > 1000, true);
  // Bad settings and a part larger than the bed: exit 2, one line, no output file.
  const std::string bad_out = (dir / "bad.gcode").string();
  for (const std::string args : {" --layer-height -1", " --fill-density 150%", " --set bogus=1",
                                 " --set bed_shape=0x0,10x0,10x10,0x10", " --temperature nan"}) {
    const CliResult b = run("slice -q " + model + " -o " + bad_out + " --planar" + args);
    EXPECT_EQ(b.code, 2) << args << ": " << b.err;
    EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
    EXPECT_FALSE(std::filesystem::exists(bad_out)) << args;
  }
  const CliResult bed =
      run("slice -q " + model + " -o " + bad_out + " --planar --set bed_shape=0x0,10x0,10x10,0x10");
  EXPECT_NE(bed.err.find("larger than the bed"), std::string::npos) << bed.err;
  // A profile file, and a broken one naming its line.
  test::write_bytes(dir / "p.ini", "layer_height = 0.3\ntemperature = 199\n");
  ASSERT_EQ(
      run("slice -q " + model + " -o " + out + " --planar --config " + (dir / "p.ini").string())
          .code,
      0);
  EXPECT_NE(test::read_bytes(out).find("M104 S199"), std::string::npos);
  test::write_bytes(dir / "q.ini", "layer_height = 0.3\nfill_density = much\n");
  const CliResult q = run("slice -q " + model + " -o " + bad_out + " --planar --config " +
                          (dir / "q.ini").string());
  EXPECT_EQ(q.code, 2);
  EXPECT_NE(q.err.find("q.ini: line 2: fill_density"), std::string::npos) << q.err;
}

TEST(Cli, SliceNonPlanarThenCheck) {
  const auto dir = test::temp_dir("cli_nonplanar");
  ASSERT_TRUE(write_stl(dir / "roof.stl", test::sine_roof()));
  const std::string model = (dir / "roof.stl").string(), out = (dir / "roof.gcode").string();
  const CliResult s = run("slice " + model + " -o " + out);
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.err.find("1 curved stack"), std::string::npos) << s.err;
  EXPECT_NE(test::read_bytes(out).find("; mode: non-planar"), std::string::npos);
  const CliResult c = run("check --json " + out + " --mesh " + model);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto j = nlohmann::json::parse(c.out);
  EXPECT_LE(j["top_surface_deviation"]["p95"].get<double>(), 0.02);
  EXPECT_EQ(j["collisions"], 0);
  EXPECT_LE(j["steepest_extrusion"].get<double>(), 30.5);
  for (const char* k : {"thickness_min", "thickness_max", "volume_ratio", "outside_fraction"})
    EXPECT_TRUE(j.contains(k)) << k;
  // A foreign file with an arc: refused with its line.
  test::write_bytes(dir / "arc.gcode", "G90\nG1 X1 Y1\nG3 X2 Y2 I1 J0 E1\n");
  const CliResult a = run("check " + (dir / "arc.gcode").string() + " --mesh " + model);
  EXPECT_EQ(a.code, 2);
  EXPECT_NE(a.err.find("line 3"), std::string::npos) << a.err;
}

// check places the mesh on the bed the file was sliced for: a PrusaSlicer file says which
// in its settings block (#16: on a 200 mm bed, check read correct files as 1-40 mm off).
TEST(Cli, CheckReadsTheBedFromTheFilesSettingsBlock) {
  const auto dir = test::temp_dir("cli_check_block");
  ASSERT_TRUE(write_stl(dir / "box.stl", test::box({0, 0, 0}, {20, 20, 5})));
  const std::string model = (dir / "box.stl").string(), out = (dir / "box.gcode").string();
  const std::string bed = "bed_shape=0x0,250x0,250x210,0x210";
  const CliResult s = run("slice -q --planar " + model + " -o " + out + " --set " + bed);
  ASSERT_EQ(s.code, 0) << s.err;
  const std::string gcode = test::read_bytes(out);
  auto outside = [&](const std::string& text, const std::string& opts) {
    test::write_bytes(dir / "t.gcode", text);
    const CliResult c =
        run("check -q --json " + (dir / "t.gcode").string() + " --mesh " + model + opts);
    EXPECT_EQ(c.code, 0) << c.err;
    return c.code == 0 ? nlohmann::json::parse(c.out)["outside_fraction"].get<double>() : -1.0;
  };
  const std::string block =
      "; prusaslicer_config = begin\n; bed_shape = 0x0,250x0,250x210,0x210\n"
      "; layer_height = 0.2\n; prusaslicer_config = end\n";
  // Our own file's header says where the part is: placed there with no block or setting.
  EXPECT_NE(gcode.find("; the part's box centred at 125.000, 105.000 mm on the bed\n"),
            std::string::npos);
  EXPECT_LT(outside(gcode, ""), 0.01);
  // Without that line (another slicer's file), the bed from the block or the user.
  std::string bare = gcode;
  const auto at = bare.find("; the part's box centred at");
  bare.erase(at, bare.find('\n', at) + 1 - at);
  EXPECT_GT(outside(bare, ""), 0.3);                // placed at (110, 110): 15 mm off
  EXPECT_LT(outside(bare + block, ""), 0.01);       // the block's bed: centred at (125, 105)
  EXPECT_LT(outside(bare, " --set " + bed), 0.01);  // or the user's
  const std::string orca =                          // OrcaSlicer's block and key name
      "; CONFIG_BLOCK_START\n; printable_area = 0x0,250x0,250x210,0x210\n; CONFIG_BLOCK_END\n";
  EXPECT_LT(outside(bare + orca, ""), 0.01);
  const std::string wrong =
      "; prusaslicer_config = begin\n; bed_shape = 0x0,1x0\n"
      "; prusaslicer_config = end\n";
  test::write_bytes(dir / "w.gcode", bare + wrong);
  const CliResult n = run("check " + (dir / "w.gcode").string() + " --mesh " + model);
  EXPECT_EQ(n.code, 0) << n.err;  // a block that does not read: a notice, and the defaults
  EXPECT_NE(n.err.find("w.gcode: its settings block is not used: "), std::string::npos) << n.err;
}

TEST(Cli, HelpAndUsage) {
  const CliResult h = run("analyze --help");
  EXPECT_EQ(h.code, 0);
  EXPECT_NE(h.out.find("--max-angle"), std::string::npos);
  EXPECT_NE(h.out.find("--export-patches"), std::string::npos);
  EXPECT_EQ(run("").code, 2);
  EXPECT_EQ(run("frobnicate").code, 2);
}

}  // namespace
}  // namespace nonplanar
