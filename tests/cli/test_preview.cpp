// `nonplanar preview` and `slice --preview` as a person uses them: the page opened in a real
// browser (Debian's chromium, headless, drawing with its software WebGL), its screenshot
// read back, and what its slider counts.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "support/cli.hpp"
#include "support/png.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

bool have_chromium() {
  return std::system("command -v chromium >/dev/null 2>&1") == 0;
}

// chromium --headless on PAGE (with #FRAGMENT): its DOM after the page has drawn, and a
// 1280 × 800 screenshot in *png.
std::string open_in_chromium(const fs::path& page, const std::string& fragment, std::string* png) {
  const fs::path dir = test::temp_dir("chromium");
  const std::string common =
      "timeout -s KILL 120 chromium --headless --no-sandbox --use-angle=swiftshader "
      "--enable-unsafe-swiftshader --disable-gpu-sandbox --user-data-dir=" +
      (dir / "profile").string() + " --window-size=1280,800 --virtual-time-budget=3000 ";
  const std::string url = "'file://" + fs::absolute(page).string() + fragment + "'";
  if (png) {
    const fs::path shot = dir / "shot.png";
    std::system(
        (common + "--screenshot=" + shot.string() + " " + url + " >/dev/null 2>&1").c_str());
    *png = test::read_bytes(shot);
  }
  std::system(
      (common + "--dump-dom " + url + " >" + (dir / "dom").string() + " 2>/dev/null").c_str());
  return test::read_bytes(dir / "dom");
}

// <body data-NAME="VALUE">, -1 when it is not there.
long body_number(const std::string& dom, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(dom, m, std::regex("data-" + name + "=\"(-?[0-9]+)\""))) return -1;
  return std::stol(m[1]);
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

fs::path sliced_roof(const fs::path& dir) {
  test::write_bytes(dir / "roof.stl", test::ascii_stl(test::sine_roof(), "\n"));
  const auto r = test::run_cli("slice " + (dir / "roof.stl").string() + " -o " +
                               (dir / "roof.gcode").string() + " --preview");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("roof.html"), std::string::npos) << r.err;
  return dir / "roof.gcode";
}

TEST(Preview, TheBrowserShowsTheCurvedLayersAndCountsOurLayers) {
  if (!have_chromium()) GTEST_SKIP() << "chromium not installed";
  const fs::path dir = test::temp_dir("preview_browser");
  const fs::path gcode = sliced_roof(dir);
  const std::string text = test::read_bytes(gcode);
  const long layers = static_cast<long>(count_of(text, ";LAYER_CHANGE"));
  ASSERT_GT(layers, 20);
  std::string png;
  const std::string dom = open_in_chromium(dir / "roof.html", "#view=front&mode=curved", &png);
  ASSERT_EQ(body_number(dom, "ready"), 1) << dom.substr(0, 2000);
  // The slider counts the file's layers, not its distinct z values (thousands here).
  EXPECT_EQ(body_number(dom, "layers"), layers);
  EXPECT_NE(dom.find("id=\"layer-hi\" type=\"range\" min=\"1\" max=\"" + std::to_string(layers)),
            std::string::npos);
  EXPECT_GT(body_number(dom, "curved-layers"), 3);
  EXPECT_LT(body_number(dom, "curved-layers"), layers);
  EXPECT_GT(body_number(dom, "drawn-pixels"), 20000);
  // The screenshot is not blank: the canvas (left of the 300 px panel) has the part in
  // curved-layer orange and planar-layer blue, not only the background and the bed grid.
  const test::Image img = test::decode_png(png);
  ASSERT_EQ(img.width, 1280);
  std::size_t orange = 0, blue = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width - 300; ++x) {
      const std::uint8_t* p = &img.rgb[(static_cast<std::size_t>(y) * img.width + x) * 3];
      if (p[0] > p[1] + 40 && p[1] > p[2] + 30) ++orange;  // the mesh over it pales it
      if (p[2] > p[0] + 40) ++blue;
    }
  EXPECT_GT(orange, 5000u);
  EXPECT_GT(blue, 5000u);
  // The slider's first position from the address: one layer.
  const std::string one = open_in_chromium(dir / "roof.html", "#layers=3-3", nullptr);
  EXPECT_EQ(body_number(one, "layer-shown"), 3);
  // While the view moves a large file is drawn from the lighter copy: made here above 10 000
  // segments, it merges runs of touching segments (3 to 10 here) and still draws the part.
  const long segments = body_number(dom, "drawn-segments");
  const std::string moving = open_in_chromium(dir / "roof.html", "#lod=10000&moving=1", nullptr);
  EXPECT_LT(body_number(moving, "drawn-segments"), segments * 2 / 3);
  EXPECT_GT(body_number(moving, "drawn-segments"), segments / 20);
  EXPECT_GT(body_number(moving, "drawn-pixels"), body_number(dom, "drawn-pixels") / 2);
}

TEST(Preview, WithTheMeshItShowsChecksFigures) {
  const fs::path dir = test::temp_dir("preview_mesh");
  const fs::path gcode = sliced_roof(dir);
  const auto r = test::run_cli("preview " + gcode.string() + " --mesh " +
                               (dir / "roof.stl").string() + " -o " + (dir / "p.html").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto c =
      test::run_cli("check -q --json " + gcode.string() + " --mesh " + (dir / "roof.stl").string());
  ASSERT_EQ(c.code, 0) << c.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(c.out, m, std::regex("\"p95\": ([0-9.e-]+)")));
  const double p95 = std::stod(m[1]);
  EXPECT_LT(p95, 0.02);
  const std::string page = test::read_bytes(dir / "p.html");
  ASSERT_TRUE(std::regex_search(page, m, std::regex("\"p95\":([0-9.e-]+)")));
  EXPECT_NEAR(std::stod(m[1]), p95, 1e-9);
  EXPECT_NE(page.find("\"collisions\":0"), std::string::npos);
  EXPECT_NE(page.find("\"mesh\":{\"box\""), std::string::npos);
  // The summary line names the page and the figures.
  EXPECT_NE(r.err.find("p.html"), std::string::npos);
  EXPECT_NE(r.err.find("curved"), std::string::npos);
}

// --section: the sine roof's beads crossing y = 110 (its middle), with its outline; no page.
// Its top is one curved stack: orange beads, and every bead inside the outline's box.
TEST(Preview, SectionDrawsTheBeadsCrossingAPlane) {
  const fs::path dir = test::temp_dir("preview_section");
  const fs::path gcode = sliced_roof(dir);
  fs::remove(dir / "roof.html");
  const fs::path svg = dir / "cut.svg";
  auto r = test::run_cli("preview -q " + gcode.string() + " --mesh " + (dir / "roof.stl").string() +
                         " --section " + svg.string() + " --at y=110");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "roof.html"));
  const std::string text = test::read_bytes(svg);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(text, m, std::regex("([0-9]+) curved layers \\(orange\\)")));
  EXPECT_GE(std::stoi(m[1]), 10);
  EXPECT_GT(count_of(text, "fill=\"#d9651b\""), 20u);  // curved beads
  EXPECT_GT(count_of(text, "<line "), 100u);           // the outline's segments
  // A plane past the part, a bad --at, --at alone, --section with -o: one line, exit 2.
  for (const std::string& args :
       {" --section " + svg.string() + " --at y=500", " --section " + svg.string() + " --at z=1",
        " --section " + svg.string() + " --at y=1mm", std::string(" --at y=110"),
        " --section " + svg.string() + " --at y=110 -o " + (dir / "p.html").string()}) {
    r = test::run_cli("preview " + gcode.string() + args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(count_of(r.err, "\n"), 1u) << r.err;
  }
}

TEST(Preview, BadInputIsOneLineAndNoPage) {
  const fs::path dir = test::temp_dir("preview_bad");
  auto r = test::run_cli("preview " + (dir / "missing.gcode").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("missing.gcode"), std::string::npos) << r.err;
  EXPECT_EQ(count_of(r.err, "\n"), 1u) << r.err;
  test::write_bytes(dir / "empty.gcode", "M104 S200\n;LAYER_CHANGE\nM107\n");
  r = test::run_cli("preview " + (dir / "empty.gcode").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("empty.gcode: no move to show"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "empty.html"));
  // The page may not be written over its own G-code.
  test::write_bytes(dir / "a.gcode", "G1 X1 Y1\n");
  r = test::run_cli("preview " + (dir / "a.gcode").string() + " -o " + (dir / "a.gcode").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(test::read_bytes(dir / "a.gcode"), "G1 X1 Y1\n");
}

}  // namespace
}  // namespace nonplanar
