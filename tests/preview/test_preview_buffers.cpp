// The preview's G-code-to-buffers step (preview/preview_buffers.cpp) on files whose every
// number can be worked out by hand, and the page that embeds them (preview_page.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <regex>
#include <string>
#include <vector>

#include "core/base64.hpp"
#include "nonplanar/preview.hpp"
#include "nonplanar/print_time.hpp"

namespace nonplanar {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Filament (1.75 mm) for a bead of width w, height h along len mm: Slic3r's section.
double e_for(double w, double h, double len) {
  const double section = (w - h) * h + kPi * h * h / 4;
  return section * len / (kPi * 1.75 * 1.75 / 4);
}

PreviewBuffers buffers_of(const std::string& gcode, const std::vector<double>& times = {}) {
  return preview_buffers(read_gcode_program(gcode), times, PreviewParams{});
}

Vec3 decoded(const PreviewBuffers& b, std::size_t seg, int end) {
  Vec3 p;
  for (int a = 0; a < 3; ++a)
    p[a] = b.box.min[a] + b.ends[6 * seg + 3 * end + a] / 65535.0 * b.box.size()[a];
  return p;
}

// Two planar layers at 0.2 mm: a purge before the first layer change, beads of known section.
std::string two_planar_layers() {
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "G90\nM82\nG92 E0\nG1 Z0.3 F600\nG1 X5 Y5 F3000\nG1 X60 Y5 E5 F1500\n"
                ";LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 Z0.2\nG1 X10 Y10 F6000\n"
                ";TYPE:External perimeter\n;WIDTH:0.45\nG1 X20 Y10 E%.5f F1200\n"
                ";TYPE:Solid infill\nG1 X20 Y20 E%.5f\nG1 E%.5f F2400\n"
                ";LAYER_CHANGE\n;Z:0.4\n;HEIGHT:0.2\nG1 Z0.4 F600\n"
                ";TYPE:External perimeter\nG1 X10 Y20 E%.5f F1200\n",
                5 + e_for(0.45, 0.2, 10), 5 + 2 * e_for(0.45, 0.2, 10),
                5 + 2 * e_for(0.45, 0.2, 10) - 0.8, 5 + 3 * e_for(0.45, 0.2, 10) - 0.8);
  return buf;
}

TEST(PreviewBuffers, CountsTheFilesLayersAndTheBeadsThickness) {
  const PreviewBuffers b = buffers_of(two_planar_layers());
  EXPECT_EQ(b.layers, 2);
  EXPECT_EQ(b.curved_layers, 0);
  // Kept: the Z move and travel of the start, the purge, the first layer's Z, travel and two
  // beads, the second layer's Z and bead. Left out: the retraction (E only).
  ASSERT_EQ(b.segments(), 9u);
  EXPECT_EQ(b.role_names,
            (std::vector<std::string>{"Custom", "External perimeter", "Solid infill"}));
  // The purge (before the first ;LAYER_CHANGE) counts as layer 0; the last bead is layer 1.
  EXPECT_EQ(b.layer[2], 0);
  EXPECT_EQ(b.layer[8], 1);
  EXPECT_EQ(b.role[8], 1);
  for (std::size_t s : {5u, 6u, 8u}) {
    EXPECT_EQ(b.flags[s] & PreviewBuffers::kTravel, 0) << s;
    EXPECT_EQ(b.thickness[s], 40) << s;  // 0.200 mm in 5 µm units
    EXPECT_EQ(b.width[s], 45) << s;      // 0.45 mm in 10 µm units
    EXPECT_EQ(b.slope[s], 0) << s;
  }
  EXPECT_NE(b.flags[4] & PreviewBuffers::kTravel, 0);  // X10 Y10 F6000
  EXPECT_EQ(b.thickness[4], 0);
  // Ends come back within the 16-bit step over the box (55 mm / 65535 < 1 µm).
  EXPECT_LT((decoded(b, 8, 0) - Vec3(20, 20, 0.4)).norm(), 2e-3);
  EXPECT_LT((decoded(b, 8, 1) - Vec3(10, 20, 0.4)).norm(), 2e-3);
  EXPECT_NEAR(b.layer_z[0], 0.2, 1e-6);
  EXPECT_NEAR(b.layer_z[1], 0.4, 1e-6);
  EXPECT_NEAR(b.filament_mm, 5 + 3 * e_for(0.45, 0.2, 10) - 0.8, 1e-4);
}

TEST(PreviewBuffers, ACurvedLayerIsOneLayerWithItsSlope) {
  // One layer whose bead climbs 1 mm over 10 mm (5.71°) and a 0.15 mm bead on the flat.
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "M83\n;LAYER_CHANGE\n;Z:0.2\n;TYPE:Top solid infill\n;WIDTH:0.5\n"
                "G1 X0 Y0 Z0.2 F3000\nG1 X10 Y0 Z1.2 E%.5f\nG1 X20 Y0 Z1.2 E%.5f\n",
                e_for(0.5, 0.3, std::hypot(10.0, 1.0)), e_for(0.5, 0.15, 10));
  const PreviewBuffers b = buffers_of(buf);
  EXPECT_EQ(b.layers, 1);
  EXPECT_EQ(b.curved_layers, 1);
  ASSERT_EQ(b.segments(), 3u);
  EXPECT_EQ(b.slope[1], 6);  // round(5.71)
  EXPECT_EQ(b.thickness[1], 60);
  EXPECT_EQ(b.thickness[2], 30);
  EXPECT_NE(b.flags[1] & PreviewBuffers::kCurvedLayer, 0);
  // Unless its span is within the tolerance.
  PreviewParams loose;
  loose.curved_span = 1.5;
  EXPECT_EQ(preview_buffers(read_gcode_program(buf), {}, loose).curved_layers, 0);
}

TEST(PreviewBuffers, TimesAreTheEstimateAtEachMovesEnd) {
  const std::string gcode = two_planar_layers();
  const GcodeProgram p = read_gcode_program(gcode);
  const PrintTime t = estimate_print_time(p, MachineLimits{});
  const PreviewBuffers b = preview_buffers(p, t.line_start, PreviewParams{});
  ASSERT_EQ(b.time.size(), b.segments());
  EXPECT_NEAR(b.seconds, t.total, 1e-9);
  for (std::size_t i = 1; i < b.time.size(); ++i) EXPECT_GE(b.time[i], b.time[i - 1]);
  EXPECT_NEAR(b.time.back(), t.total, 1e-3);  // the last line is the last bead
  EXPECT_GT(b.time.front(), 0);
}

TEST(PreviewBuffers, AnEmptyLastLayerIsAtItsZ) {
  const PreviewBuffers b = buffers_of(two_planar_layers() + ";LAYER_CHANGE\n;Z:0.6\n;HEIGHT:0.2\n");
  EXPECT_EQ(b.layers, 3);
  ASSERT_EQ(b.layer_z.size(), 3u);
  EXPECT_NEAR(b.layer_z[2], 0.6, 1e-6);
}

TEST(PreviewBuffers, NoMoveNoSegment) {
  const PreviewBuffers b = buffers_of("M104 S200\n;LAYER_CHANGE\nG1 E1 F300\n");
  EXPECT_EQ(b.segments(), 0u);
  EXPECT_EQ(b.layers, 0);
}

std::string json_string(const std::string& page, const std::string& key) {
  const auto at = page.find("\"" + key + "\":\"");
  if (at == std::string::npos) return "";
  const auto from = at + key.size() + 4;
  return page.substr(from, page.find('"', from) - from);
}

TEST(PreviewPage, EmbedsTheBuffersAndStaysOneDocument) {
  PreviewBuffers b = buffers_of(two_planar_layers());
  b.role_names.push_back("</script><b>");  // a hostile ;TYPE: must not end the data
  PreviewSummary s;
  s.title = "a</script>.gcode";
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 1}};
  mesh.faces = {{0, 1, 2}};
  const std::string page = preview_html(b, &mesh, PreviewMarks{{Vec3(1, 2, 3)}, {}}, s);
  std::size_t closes = 0;
  for (auto at = page.find("</script>"); at != std::string::npos;
       at = page.find("</script>", at + 1))
    ++closes;
  EXPECT_EQ(closes, 2u);  // the data element's and the viewer's
  EXPECT_EQ(page.find("/*NP_DATA*/"), std::string::npos);
  EXPECT_NE(page.find("\"layers\":2"), std::string::npos);
  EXPECT_NE(page.find("\"segments\":9"), std::string::npos);
  // The arrays are the buffers' bytes.
  const std::string layer(reinterpret_cast<const char*>(b.layer.data()), b.layer.size() * 2);
  EXPECT_EQ(json_string(page, "layer"), core::base64_encode(layer));
  // The mark (1, 2, 3) as three little-endian floats.
  const std::string m = json_string(page, "collisions");
  EXPECT_EQ(
      m, core::base64_encode(std::string("\x00\x00\x80\x3f\x00\x00\x00\x40\x00\x00\x40\x40", 12)));
}

TEST(Base64, MatchesTheRfcVectors) {
  EXPECT_EQ(core::base64_encode(""), "");
  EXPECT_EQ(core::base64_encode("f"), "Zg==");
  EXPECT_EQ(core::base64_encode("fo"), "Zm8=");
  EXPECT_EQ(core::base64_encode("foo"), "Zm9v");
  EXPECT_EQ(core::base64_encode("foobar"), "Zm9vYmFy");
}

// The beads in a vertical plane (preview/bead_section.cpp), crossings worked out by hand.

// A purge line, then two layers: a line across y = 5 square to it, one at 45° to it, and one
// along it (which does not cross it). The second layer is curved: it rises 0.1 mm along x.
std::string two_layers() {
  const double a = e_for(0.45, 0.2, 10), d = e_for(0.45, 0.2, std::sqrt(200.0));
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "G90\nM83\nG1 Z0.3 F600\nG1 X0 Y5 F3000\nG1 X60 Y5 E5 F1500\n"
                ";LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 Z0.2\nG1 X2 Y0 F6000\n"
                ";TYPE:External perimeter\n;WIDTH:0.45\nG1 X2 Y10 E%.5f F1200\n"
                "G1 X12 Y0 E%.5f\nG1 X2 Y5 F6000\nG1 X12 Y5 E%.5f\n"
                ";LAYER_CHANGE\n;Z:0.4\n;HEIGHT:0.2\nG1 X2 Y0 Z0.4 F6000\n"
                "G1 X2 Y10 E%.5f F1200\nG1 X12 Y0 Z0.5 E%.5f\n",
                a, d, a, a, d);
  return buf;
}

struct Rect {
  double x, y, w, h;
};

std::vector<Rect> rects(const std::string& svg) {
  std::vector<Rect> out;
  const std::regex r(
      "<rect x=\"([-0-9.]+)\" y=\"([-0-9.]+)\" width=\"([-0-9.]+)\" height=\"([-0-9.]+)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), r); it != std::sregex_iterator();
       ++it)
    out.push_back(
        {std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3]), std::stod((*it)[4])});
  return out;
}

TEST(BeadSection, DrawsEachCrossingAsItsBeadsSection) {
  const PreviewBuffers b = preview_buffers(read_gcode_program(two_layers()), {}, PreviewParams{});
  auto svg = bead_section_svg(b, nullptr, 'y', 5.0);
  ASSERT_TRUE(svg) << svg.error().message;
  // Two crossings a layer; not the purge line along y = 5, nor the line lying in the plane.
  const std::vector<Rect> r = rects(*svg);
  ASSERT_EQ(r.size(), 4u);
  // Widths in the plane: 0.45 square to it, 0.45 / sin 45° at 45°; heights 0.2 (px = mm ·
  // scale, the scale from the first bead).
  const double scale = r[0].w / 0.45;
  EXPECT_NEAR(r[0].h / scale, 0.2, 0.01);
  EXPECT_NEAR(r[1].w / scale, 0.45 * std::sqrt(2.0), 0.01);
  // The second layer's bead at 45° crosses at x = 7, half-way up its rise: its top at 0.45.
  EXPECT_NEAR((r[3].y - r[2].y) / scale, -0.05, 0.005);
  EXPECT_NE(svg->find("1 curved layers (orange), 1 planar (blue)"), std::string::npos);
}

TEST(BeadSection, SaysWhenNothingCrossesThePlane) {
  const PreviewBuffers b = preview_buffers(read_gcode_program(two_layers()), {}, PreviewParams{});
  auto svg = bead_section_svg(b, nullptr, 'x', 50.0);
  ASSERT_FALSE(svg);
  EXPECT_EQ(svg.error().status, Status::invalid_argument);
  EXPECT_NE(svg.error().message.find("no extrusion crosses x = 50"), std::string::npos);
  EXPECT_FALSE(bead_section_svg(b, nullptr, 'z', 1.0));
}

}  // namespace
}  // namespace nonplanar
