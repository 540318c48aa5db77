// One libFuzzer target per parser: this file is compiled once per parser with
// NONPLANAR_FUZZ_PARSER set to its number (see fuzz/CMakeLists.txt). Every parser must return
// an Error for bad input; a crash, hang, leak or sanitizer report is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/readers.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/surface_io.hpp"
#include "nonplanar/toolhead.hpp"

#if NONPLANAR_FUZZ_PARSER == 8
#include <cmath>
namespace {
// Layers 0.2 mm thick at x = 0, thicker and thinner along x (every column curved), so the
// mapper resamples, scales and lifts as it does over a stack.
struct Wave final : nonplanar::LayerField {
  static double k(double x) { return 0.2 * (1 + 0.2 * std::sin(x / 5)); }
  double T(double x, double, double z) const override { return z / k(x); }
  double z_at(double x, double, double t) const override { return t * k(x); }
  double zeta(double t) const override { return 0.2 * t; }
  double t_of_zeta(double z) const override { return z / 0.2; }
  double thickness(double x, double, double) const override { return k(x); }
  bool planar_at(double, double) const override { return false; }
};
// The shell's core cut back: kept on a wavy region up to z = 5, nothing above z = 10.
struct Waves final : nonplanar::LayerClip {
  Cover cover(double z) const override {
    return z < 2 ? Cover::all : z > 10 ? Cover::none : Cover::some;
  }
  double margin(double x, double y, double z) const override {
    return std::sin(x / 3) + std::cos(y / 4) - 0.2 * z;
  }
};
}  // namespace
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nonplanar;
  const std::string_view in(reinterpret_cast<const char*>(data), size);
#if NONPLANAR_FUZZ_PARSER == 0
  MeshFormat f;
  (void)io::parse_stl(in, &f);
#elif NONPLANAR_FUZZ_PARSER == 1
  (void)io::parse_obj(in);
#elif NONPLANAR_FUZZ_PARSER == 2
  (void)io::parse_off(in);
#elif NONPLANAR_FUZZ_PARSER == 3
  (void)io::parse_3mf(in);
#elif NONPLANAR_FUZZ_PARSER == 4
  (void)parse_ini_config(in);
#elif NONPLANAR_FUZZ_PARSER == 5
  (void)parse_json_config(in);
#elif NONPLANAR_FUZZ_PARSER == 6
  (void)parse_surfaces_json(in);
#elif NONPLANAR_FUZZ_PARSER == 7
  (void)read_gcode_moves(in);
#elif NONPLANAR_FUZZ_PARSER == 8
  static const Wave field;
  (void)map_foreign_gcode(in, field, {}, {});
  static const Waves clip;
  ForeignMapOptions o;
  o.clip = &clip;
  o.start = Vec3(100, 100, 3);
  o.start_retracted = 0.8;
  (void)map_foreign_gcode(in, field, {}, {}, o);
#elif NONPLANAR_FUZZ_PARSER == 9
  // A head file that parses must also answer the collision search's queries.
  const auto shape = parse_toolhead_shape(in);
  if (!shape) return 0;
  Toolhead t;
  t.shape = *shape;
  const HeadClearance head(t), low(t, 2.0);
  for (const Vec2& d : {Vec2(0, 0), Vec2(3, -4), Vec2(-25, 10)})
    (void)head.allowance(d), (void)low.allowance(d), (void)head.block_allowance(d);
  (void)head.allowance_lower_bound(Vec2(-10, -10), Vec2(10, 10));
  (void)t.describe();
#else
#error "NONPLANAR_FUZZ_PARSER must name a parser (0-9)"
#endif
  return 0;
}
